#pragma once
// A scene for suture tests (issue 8): a soft cantilever beam whose cut opens
// under gravity, then sutures along the cut; and the gap across the cut.
#include <algorithm>
#include <vector>

#include "core/model/model.h"
#include "core/scenario/scenario.h"
#include "core/run/run.h"

namespace organsim::testing {

// An 8 x 2 x 2 cm beam (8 x 2 x 2 cubes of 1 cm) held at x = 0, sagging
// under gravity. From 0 to 10 ms a blade along y in the grid plane x = 2 cm
// cuts down from the top to z = 0.5 cm; the cut opens as the beam sags. At
// `tie` s sutures along it (one every 5 mm, 300 N/m, tightening at 5 cm/s to
// zero length) close it.
inline Scenario sutured_beam(double tie = 0.3, double duration = 1.3) {
  Scenario s;
  s.file = "sutured_beam.json";
  s.material.density = 1000;
  s.material.young_modulus = 5000;
  s.material.spring_damping_time = 1e-3;
  s.material.volume_modulus = 10000;
  s.material.viscous_damping = 5;
  FixedSelector root;
  root.kind = FixedSelector::Kind::Plane;
  root.point = Vec3(1e-6, 0, 0);
  root.normal = Vec3(-1, 0, 0);
  s.fixed = {root};
  s.gravity = Vec3(0, 0, -9.81);
  s.time.duration = duration;
  s.time.dt = 1e-4;
  s.time.substeps = 10;
  CutEvent cut;
  cut.name = "incision";
  cut.keyframes = {{0.0, Vec3(0.02, -0.01, 0.025), Vec3(0.02, 0.03, 0.025)},
                   {0.01, Vec3(0.02, -0.01, 0.005), Vec3(0.02, 0.03, 0.005)}};
  s.events.cuts = {cut};
  SutureEvent suture;
  suture.where = "sutured_beam.json: events[1].suture";
  suture.t = tie;
  suture.stiffness = 300;
  suture.along = "incision";
  suture.spacing = 0.005;
  suture.max_distance = 0.03;
  suture.rate = 0.05;
  suture.min_length = 0;
  s.events.sutures = {suture};
  return s;
}

inline Model beam_model(const Scenario& s) {
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3(0.08, 0.02, 0.02), 8, 2, 2), s.material,
                     model_options(s), "beam");
}

// The widest opening of the cut: the largest distance between two copies of
// the same mesh point, among the first x.size() points of `model` (whose
// origins say which points are copies), m.
inline double cut_gap(const Model& model, const std::vector<Vec3>& x) {
  auto root = [&](int32_t p) {
    while (model.origin[p] != p) p = model.origin[p];
    return p;
  };
  double gap = 0;
  for (int32_t p = model.mesh_points; p < static_cast<int32_t>(x.size()); ++p) {
    const int32_t r = root(p);
    gap = std::max(gap, (x[p] - x[r]).norm());
    for (int32_t q = model.mesh_points; q < p; ++q)
      if (root(q) == r) gap = std::max(gap, (x[p] - x[q]).norm());
  }
  return gap;
}

}  // namespace organsim::testing
