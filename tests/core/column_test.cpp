// A column fixed at the top hangs under gravity and settles to the static
// elongation its springs predict.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "core/sim/cpu_backend.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace column_test {
namespace {

TEST(HangingColumn, ChainSettlesToAnalyticElongation) {
  // N masses in a vertical chain, top one fixed. Spring j (from the top)
  // carries the weight of the N-1-j masses below it: stretch (N-1-j) m g / k.
  const int n = 10;
  const double m = 0.01, k = 50, rest = 0.01, g = 9.81;
  std::vector<Vec3> points;
  std::vector<Edge> springs;
  for (int i = 0; i < n; ++i) points.push_back(Vec3(0, 0, -rest * i));
  for (int i = 0; i + 1 < n; ++i) springs.push_back({i, i + 1});
  Model model = testing::make_spring_model(points, std::vector<double>(n, m), springs, k, 0.0, {0}, Vec3(0, 0, -g));
  model.viscous_damping = 22;  // 1/s: about critical for the lowest mode (11 rad/s)
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  testing::run_ticks(*backend, 3000, 1e-4, 10);  // 3 s
  std::vector<Vec3> pos;
  backend->positions(pos);
  double expected_z = 0;
  for (int j = 0; j + 1 < n; ++j) {
    expected_z -= rest + (n - 1 - j) * m * g / k;
    // Statics are exact for Verlet (F = 0 is its fixed point); 1e-9 m covers
    // the remaining exp(-11 * 3) transient.
    EXPECT_NEAR(pos[j + 1].z(), expected_z, 1e-9) << "point " << j + 1;
  }
}

// Linear static displacement K u = f of the spring network at rest (the
// small-strain truth the dynamic run must settle to).
std::vector<Vec3> linear_static_sag(const Model& model) {
  const int n = model.npoint();
  std::vector<int> dof(n, -1);
  int ndof = 0;
  for (int i = 0; i < n; ++i)
    if (!model.fixed[i]) dof[i] = ndof++;
  std::vector<Eigen::Triplet<double>> triplets;
  for (int s = 0; s < model.nspring(); ++s) {
    const auto [a, b] = model.spring_ends[s];
    const Vec3 u = (model.rest_position[b] - model.rest_position[a]).normalized();
    const Eigen::Matrix3d ke = model.spring_k[s] * u * u.transpose();
    const int ends[2] = {a, b};
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) {
        if (dof[ends[i]] < 0 || dof[ends[j]] < 0) continue;
        const double sign = i == j ? 1 : -1;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            triplets.emplace_back(3 * dof[ends[i]] + r, 3 * dof[ends[j]] + c, sign * ke(r, c));
      }
  }
  Eigen::SparseMatrix<double> K(3 * ndof, 3 * ndof);
  K.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * ndof);
  for (int i = 0; i < n; ++i)
    if (dof[i] >= 0) f.segment<3>(3 * dof[i]) = model.mass[i] * model.gravity;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(K);
  EXPECT_EQ(solver.info(), Eigen::Success);
  const Eigen::VectorXd u = solver.solve(f);
  std::vector<Vec3> displacement(n, Vec3::Zero());
  for (int i = 0; i < n; ++i)
    if (dof[i] >= 0) displacement[i] = u.segment<3>(3 * dof[i]);
  return displacement;
}

TEST(HangingColumn, TetColumnMatchesLinearStatics) {
  // 2 x 2 x 10 cm column, E = 1 MPa: axial strain ~ rho g L / E ~ 0.1 %.
  // The Kuhn lattice also sways sideways under its own weight, and the
  // tension then stiffens that sway (geometric stiffness the linear solve
  // lacks); at 100 kPa that alone made 14 %, at 1 MPa it is ~1.5 %:
  // tolerance 3 % of the peak displacement.
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.02, 0.02, 0.1), 2, 2, 10);
  Material material;
  material.density = 1000;
  material.young_modulus = 1e6;
  material.spring_damping_time = 0;
  // 1/s: about critical for the slowest (sway, ~60 rad/s) mode; faster
  // modes decay as exp(-60 t), so 0.5 s leaves exp(-30) of the transient.
  material.viscous_damping = 120;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  FixedSelector top;
  top.kind = FixedSelector::Kind::Plane;
  top.point = Vec3(0, 0, 0.1 - 1e-9);
  top.normal = Vec3(0, 0, 1);
  options.fixed.push_back(top);
  const Model model = build_model(mesh, material, options);
  const std::vector<Vec3> expected = linear_static_sag(model);

  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  testing::run_ticks(*backend, 500, 2e-5, 50);  // 0.5 s
  std::vector<Vec3> pos;
  backend->positions(pos);
  double peak = 0, worst = 0;
  for (int i = 0; i < model.npoint(); ++i) {
    peak = std::max(peak, expected[i].norm());
    worst = std::max(worst, (pos[i] - model.rest_position[i] - expected[i]).norm());
  }
  ASSERT_GT(peak, 1e-6);  // the column does sag measurably
  EXPECT_LT(worst, 0.03 * peak) << "peak sag " << peak << " m";
}

}  // namespace
}  // namespace column_test
}  // namespace organsim
