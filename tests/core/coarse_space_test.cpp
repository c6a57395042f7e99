// The two-level preconditioner's coarse space (core/sim/coarse_space.h):
// its aggregates cover every free point once and hold together over the
// springs, its correction P A_c^-1 P^T is symmetric and reproduces any rigid
// motion of the free points exactly (translations and rotations are in its
// range, and A_c is P^T A P), a mode an aggregate cannot carry is dropped,
// and implicit Euler with it solves the same steps as with block Jacobi in
// fewer CG iterations on a stiff block.
#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "core/model/rest_stiffness.h"
#include "core/sim/coarse_space.h"
#include "core/sim/reference_backend.h"
#include "tests/core/force_law_checks.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace {

constexpr double kH = 1e-3;

Model stiff_box(int cells) {
  Material material = testing::soft_material(0.45);
  material.young_modulus = 1e6;
  material.spring_damping_time = 0.002;
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), cells, cells, cells), material,
                     testing::fixed_bottom_options(Vec3(0, 0, -9.81)));
}

// M + h D_rest + h^2 K_rest, assembled as the coarse space projects it.
Eigen::SparseMatrix<double> rest_system(const Model& model) {
  Triplets t = rest_stiffness(model);
  for (auto& e : t) e = {e.row(), e.col(), kH * kH * e.value()};
  for (const auto& e : rest_damping(model)) t.emplace_back(e.row(), e.col(), kH * e.value());
  for (int32_t i = 0; i < model.npoint(); ++i)
    for (int a = 0; a < 3; ++a) t.emplace_back(3 * i + a, 3 * i + a, model.mass[i]);
  return assemble(model, t);
}

Eigen::VectorXd correction(CoarseSpace& coarse, const Eigen::VectorXd& r) {
  Eigen::VectorXd z = Eigen::VectorXd::Zero(r.size());
  coarse.add_correction(r, z);
  return z;
}

TEST(CoarseSpace, AggregatesCoverEveryFreePointOnceAndHoldTogetherOverTheSprings) {
  const Model model = stiff_box(6);
  const CoarseSpace coarse(model);
  const std::vector<int32_t>& of = coarse.aggregate_of();
  ASSERT_EQ(of.size(), static_cast<size_t>(model.npoint()));
  // Union-find over the springs inside an aggregate: one component each.
  std::vector<int32_t> parent(model.npoint());
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int32_t p) {
    while (parent[p] != p) p = parent[p] = parent[parent[p]];
    return p;
  };
  for (const auto& [a, b] : model.spring_ends)
    if (of[a] >= 0 && of[a] == of[b]) parent[root(a)] = root(b);
  std::vector<int32_t> component_of(coarse.aggregates(), -1);
  for (int32_t p = 0; p < model.npoint(); ++p) {
    if (model.fixed[p]) {
      EXPECT_EQ(of[p], -1) << "fixed point " << p;
      continue;
    }
    ASSERT_GE(of[p], 0) << "free point " << p;
    ASSERT_LT(of[p], coarse.aggregates());
    if (component_of[of[p]] < 0) component_of[of[p]] = root(p);
    EXPECT_EQ(root(p), component_of[of[p]]) << "aggregate " << of[p] << " falls apart at point " << p;
  }
  for (int32_t a = 0; a < coarse.aggregates(); ++a) EXPECT_GE(component_of[a], 0) << "empty aggregate " << a;
  // Two-spring neighbourhoods: several per model, far fewer than points.
  EXPECT_GT(coarse.aggregates(), 1);
  EXPECT_LT(coarse.aggregates(), model.npoint() / 8);
  EXPECT_EQ(coarse.modes(), 6 * coarse.aggregates());  // every aggregate spans 3-D: all six rigid modes
}

TEST(CoarseSpace, TheCorrectionIsSymmetricAndReproducesEveryRigidMotionOfTheFreePoints) {
  const Model model = stiff_box(5);
  CoarseSpace coarse(model);
  coarse.factor(kH, kH * kH);
  const Eigen::SparseMatrix<double> a = rest_system(model);
  const int32_t n = model.npoint();
  const Vec3 translation(1e-3, -2e-3, 0.5e-3), omega(0.3, -0.1, 0.2);
  Eigen::VectorXd rigid = Eigen::VectorXd::Zero(3 * n), bent = rigid;
  for (int32_t p = 0; p < n; ++p) {
    if (model.fixed[p]) continue;
    const Vec3& x = model.rest_position[p];
    rigid.segment<3>(3 * p) = translation + omega.cross(x);
    bent.segment<3>(3 * p) = Vec3(x.z() * x.z(), 0, x.x() * x.y());
  }
  // u in the range of P: P A_c^-1 P^T A u = P A_c^-1 A_c c = u (rounding:
  // A_c's condition number times 1e-16).
  const Eigen::VectorXd back = correction(coarse, a * rigid);
  EXPECT_LT((back - rigid).norm(), 1e-9 * rigid.norm());
  // A bending field is not: the correction is no identity.
  EXPECT_GT((correction(coarse, a * bent) - bent).norm(), 1e-3 * bent.norm());
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  Eigen::VectorXd r1(3 * n), r2(3 * n);
  for (int32_t i = 0; i < 3 * n; ++i) r1[i] = normal(rng), r2[i] = normal(rng);
  const Eigen::VectorXd z1 = correction(coarse, r1), z2 = correction(coarse, r2);
  EXPECT_NEAR(r1.dot(z2), r2.dot(z1), 1e-12 * r1.norm() * z2.norm());
  EXPECT_GT(r1.dot(z1), 0);
  for (int32_t p = 0; p < n; ++p)
    if (model.fixed[p]) {
      EXPECT_EQ(z1.segment<3>(3 * p).norm(), 0) << "fixed point " << p;
    }
}

// Four points on a line: no rotation about the line moves them, so that
// mode is dropped and the coarse system stays positive definite.
TEST(CoarseSpace, AModeAnAggregateCannotCarryIsDropped) {
  const Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0.02, 0, 0), Vec3(0.03, 0, 0)},
                                                 {0.01, 0.01, 0.01, 0.01}, {{0, 1}, {1, 2}, {2, 3}}, 100, 0.1, {});
  CoarseSpace coarse(model);
  EXPECT_EQ(coarse.modes(), 5 * coarse.aggregates());
  coarse.factor(kH, kH * kH);
  Eigen::VectorXd shift = Eigen::VectorXd::Zero(12);
  for (int p = 0; p < 4; ++p) shift.segment<3>(3 * p) = Vec3(0, 1e-3, 2e-3);
  EXPECT_LT((correction(coarse, rest_system(model) * shift) - shift).norm(), 1e-9 * shift.norm());
}

// Both preconditioners solve the same steps (tolerance 1e-9: the runs agree
// within 1e-6 of the largest displacement), and on a stiff block the coarse
// correction saves most of block Jacobi's iterations.
TEST(ImplicitEuler, TwoLevelAndBlockJacobiAgreeAndTheCoarseCorrectionNeedsFewerIterations) {
  const Model model = stiff_box(10);
  std::vector<std::vector<Vec3>> end(2);
  std::vector<int64_t> iterations(2);
  for (int k = 0; k < 2; ++k) {
    ImplicitOptions options;
    options.preconditioner = k == 0 ? Preconditioner::BlockJacobi : Preconditioner::TwoLevel;
    options.cg_tolerance = 1e-9;
    options.cg_max_iterations = 2000;
    auto backend = make_reference_backend(model, {}, Integrator::ImplicitEuler, options);
    testing::run_ticks(*backend, 20, kH, 1);
    backend->positions(end[k]);
    for (int32_t it : backend->integrator_stats()->cg_iterations) iterations[k] += it;
  }
  double largest = 0, worst = 0;
  for (int32_t p = 0; p < model.npoint(); ++p) {
    largest = std::max(largest, (end[0][p] - model.rest_position[p]).norm());
    worst = std::max(worst, (end[0][p] - end[1][p]).norm());
  }
  EXPECT_GT(largest, 0);
  EXPECT_LT(worst, 1e-6 * largest);
  EXPECT_LT(iterations[1], iterations[0] * 3 / 5) << "block Jacobi " << iterations[0] << ", two-level " << iterations[1];
}

}  // namespace
}  // namespace organsim
