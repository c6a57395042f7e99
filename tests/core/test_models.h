#pragma once
// Small hand-built models for physics tests (no meshing needed).
#include <cmath>
#include <random>

#include "core/mesh/tet_mesh.h"
#include "core/model/layout_build.h"
#include "core/model/model.h"
#include "core/model/model_rebuild.h"
#include "core/sim/backend.h"
#include "core/sim/cpu_backend.h"

namespace organsim::testing {

// One CPU thread, for tests whose subject is not the thread count: results
// are bit-identical on any count, and the automatic choice times both counts
// at construction and re-times them during a run, which on a loaded shared
// machine costs more than the test itself.
inline CpuBackendOptions one_thread() { return {Precision::Double, 1}; }

// The bottom face (z <= 0) held, with gravity and a chunk size.
inline ModelOptions fixed_bottom_options(const Vec3& gravity = Vec3::Zero(), int32_t chunk = kDefaultChunkSize) {
  ModelOptions options;
  options.gravity = gravity;
  options.chunk_size = chunk;
  FixedSelector base;
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-9);
  base.normal = Vec3(0, 0, -1);
  options.fixed.push_back(base);
  return options;
}

// Points joined by explicit springs (no tets): masses in kg, k in N/m, d in N s/m.
inline Model make_spring_model(const std::vector<Vec3>& points, const std::vector<double>& masses,
                               const std::vector<Edge>& springs, double k, double d,
                               const std::vector<int32_t>& fixed_points, const Vec3& gravity = Vec3::Zero()) {
  Model m;
  const int32_t n = static_cast<int32_t>(points.size());
  m.rest_position = points;
  m.mass = masses;
  m.fixed.assign(n, 0);
  for (int32_t p : fixed_points) m.fixed[p] = 1;
  m.inv_mass.resize(n);
  for (int32_t i = 0; i < n; ++i) m.inv_mass[i] = m.fixed[i] ? 0 : 1 / masses[i];
  for (int32_t i = 0; i < n; ++i) {
    m.input_of_internal.push_back(i);
    m.internal_of_input.push_back(i);
  }
  for (const Edge& e : springs) {
    m.spring_ends.push_back({std::min(e[0], e[1]), std::max(e[0], e[1])});
    m.spring_rest.push_back((points[e[1]] - points[e[0]]).norm());
    m.spring_k.push_back(k);
    m.spring_d.push_back(d);
  }
  m.gravity = gravity;
  m.layout = build_gather_layout(m, 16, 4);  // chunks of one register of the widest target's floats
  return m;
}

// A box tet mesh with its interior points jittered by up to `jitter` of a cell.
inline TetMesh jittered_box(int n, double size, double jitter, unsigned seed) {
  TetMesh mesh = make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(size), n, n, n);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const double h = size / n;
  for (Vec3& p : mesh.points) {
    const bool interior = (p.array() > 1e-12).all() && (p.array() < size - 1e-12).all();
    if (interior) p += jitter * h * Vec3(u(rng), u(rng), u(rng));
  }
  return mesh;
}

// Separates a grid-aligned box model along the plane x = x_cut, which must be
// a plane of tet faces: tets whose centroid lies beyond it take a copy of
// every point on the plane (a through cut made by hand, for rebuild tests).
inline TopologyChange split_across_plane_x(const Model& model, double x_cut) {
  TopologyChange change;
  change.tet_points = model.tet_points;
  std::vector<int32_t> copy_of(model.npoint(), -1);
  for (Tet& tet : change.tet_points) {
    Vec3 centroid = Vec3::Zero();
    for (int32_t p : tet) centroid += model.rest_position[p] / 4;
    if (centroid.x() < x_cut) continue;
    for (int32_t& p : tet) {
      if (std::abs(model.rest_position[p].x() - x_cut) > 1e-9) continue;
      if (copy_of[p] < 0) {
        copy_of[p] = model.npoint() + static_cast<int32_t>(change.appended_origin.size());
        change.appended_origin.push_back(p);
      }
      p = copy_of[p];
    }
  }
  return change;
}

inline void run_ticks(Backend& backend, int ticks, double dt, int substeps) {
  TickRequest request;
  request.dt = dt;
  request.substeps = substeps;
  for (int i = 0; i < ticks; ++i) backend.tick(request);
}

}  // namespace organsim::testing
