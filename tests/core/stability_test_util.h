#pragma once
// Helpers for the stability tests: small models and an empirical stability
// probe (does a tiny random perturbation grow under the CPU backend?).
#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "core/model/model.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "tests/core/test_models.h"

namespace organsim::testing {

// A box of n^3 cubes (6 tets each), edge `size` m, bottom face (z = 0) fixed.
inline Model stability_box(int n, double size, const Material& material, double jitter = 0, unsigned seed = 1) {
  TetMesh mesh = jitter > 0 ? jittered_box(n, size, jitter, seed)
                            : make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(size), n, n, n);
  ModelOptions options;
  FixedSelector bottom;
  bottom.kind = FixedSelector::Kind::Plane;
  bottom.point = Vec3(0, 0, 1e-9 * size);
  bottom.normal = Vec3(0, 0, -1);  // fixed where z <= 0
  options.fixed.push_back(bottom);
  return build_model(mesh, material, options);
}

// The rest stiffness K of the whole model by central differences of the
// reference force (dense; ~100 points), restricted to the free points.
inline Eigen::MatrixXd dense_rest_stiffness(const Model& model, std::vector<int32_t>& free_dof) {
  free_dof.clear();
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i])
      for (int k = 0; k < 3; ++k) free_dof.push_back(3 * i + k);
  const int n = static_cast<int>(free_dof.size());
  Eigen::MatrixXd K(n, n);
  std::vector<Vec3> zero(model.npoint(), Vec3::Zero()), plus, minus;
  const double h = 1e-7;
  for (int c = 0; c < n; ++c) {
    std::vector<Vec3> x = model.rest_position;
    x[free_dof[c] / 3][free_dof[c] % 3] += h;
    reference_internal_forces(model, x, zero, plus);
    x[free_dof[c] / 3][free_dof[c] % 3] -= 2 * h;
    reference_internal_forces(model, x, zero, minus);
    for (int r = 0; r < n; ++r) K(r, c) = -(plus[free_dof[r] / 3][free_dof[r] % 3] - minus[free_dof[r] / 3][free_dof[r] % 3]) / (2 * h);
  }
  return 0.5 * (K + K.transpose());
}

inline Material undamped_material(double young = 3000, double volume_modulus = 0) {
  Material m;
  m.density = 1000;
  m.young_modulus = young;
  m.spring_damping_time = 0;
  m.viscous_damping = 0;
  m.volume_modulus = volume_modulus;
  return m;
}

// True when a perturbation of relative size 1e-6 of the model's extent grows
// by 1e4 (or turns non-finite) within `steps` steps of dt.
inline bool perturbation_grows(const Model& model, double dt, int steps = 3000) {
  auto backend = make_cpu_backend(model, {}, one_thread());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const double scale = 1e-6 * (model.rest_position.front() - model.rest_position.back()).norm();
  std::vector<Vec3> x = model.rest_position;
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i]) x[i] += scale * Vec3(u(rng), u(rng), u(rng));
  backend->set_state(x, x);
  TickRequest request;
  request.dt = dt;
  request.substeps = 50;
  std::vector<Vec3> pos;
  for (int s = 0; s < steps; s += request.substeps) {
    backend->tick(request);
    backend->positions(pos);
    for (int32_t i = 0; i < model.npoint(); ++i) {
      const double d = (pos[i] - model.rest_position[i]).norm();
      if (!std::isfinite(d) || d > 1e4 * scale) return true;
    }
  }
  return false;
}

}  // namespace organsim::testing
