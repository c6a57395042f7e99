#pragma once
// Small box scenes shared by the GL tests (built from make_box_tet_mesh so
// the tests need neither CGAL nor the scenario files).
#include <random>
#include <vector>

#include "core/mesh/tet_mesh.h"
#include "core/model/model.h"
#include "core/sim/backend.h"
#include "core/sim/run_observer.h"

namespace organsim::gl_test {

// A 0.1 x 0.1 x 0.05 m soft box (E = 3 kPa, liver-like), nx x ny x nz cubes.
// fixed_bottom: the z = 0 face is fixed. volume_modulus 0 turns the volume pass off.
inline Model box_model(int nx, int ny, int nz, bool fixed_bottom, double volume_modulus, const Vec3& gravity,
                       double viscous_damping = 1.0) {
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.05), nx, ny, nz);
  Material material;
  material.volume_modulus = volume_modulus;
  material.viscous_damping = viscous_damping;
  ModelOptions options;
  options.gravity = gravity;
  if (fixed_bottom) {
    FixedSelector bottom;
    bottom.kind = FixedSelector::Kind::Plane;
    bottom.point = Vec3(0, 0, 1e-9);
    bottom.normal = Vec3(0, 0, -1);  // points with z <= 1e-9
    options.fixed.push_back(bottom);
  }
  return build_model(mesh, material, options, "test box");
}

inline double bbox_diagonal(const Model& model) {
  Vec3 lo = model.rest_position[0], hi = lo;
  for (const Vec3& x : model.rest_position) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  return (hi - lo).norm();
}

// Positions rounded to float, as the GPU stores them: references evaluated
// at these see the same input, so only arithmetic differences remain.
inline std::vector<Vec3> round_to_float(const std::vector<Vec3>& x) {
  std::vector<Vec3> r(x.size());
  for (size_t i = 0; i < x.size(); ++i) r[i] = x[i].cast<float>().cast<double>();
  return r;
}

// Rest positions displaced by uniform noise of +-amplitude per coordinate, m.
inline std::vector<Vec3> perturbed(const Model& model, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  std::vector<Vec3> x = model.rest_position;
  for (Vec3& p : x) p += Vec3(u(rng), u(rng), u(rng));
  return round_to_float(x);
}

// Counts a run's topology changes and keeps its final positions.
struct FinalState final : RunObserver {
  std::vector<Vec3> x;
  int changes = 0;
  void on_tick(const Model&, Backend&, const TickInfo&) override {}
  void on_topology_changed(const Model&, Backend&) override { ++changes; }
  void on_finish(const Model&, Backend& backend) override { backend.positions(x); }
};

}  // namespace organsim::gl_test
