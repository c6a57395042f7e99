// The two-level preconditioner's coarse space (core/sim/coarse_space.h):
// its aggregates cover every free point once and hold together over the
// springs, its correction P A_c^-1 P^T is symmetric and reproduces any rigid
// motion of the free points exactly (translations and rotations are in its
// range, and A_c is P^T A P), and a mode an aggregate cannot carry is
// dropped. (Implicit Euler with it: implicit_test.cpp.)
#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "core/model/rest_stiffness.h"
#include "core/sim/coarse_space.h"
#include "tests/core/force_law_checks.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace coarse_space_test {
namespace {

constexpr double kH = 1e-3;

Model stiff_box(int cells) {
  Material material = testing::soft_material(0.45);
  material.young_modulus = 1e6;
  material.spring_damping_time = 0.002;
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), cells, cells, cells), material,
                     testing::fixed_bottom_options(Vec3(0, 0, -9.81)));
}

Eigen::SparseMatrix<double> rest_system(const Model& model) {
  return assemble(model, organsim::rest_system(model, kH, kH * kH));
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

}  // namespace
}  // namespace coarse_space_test
}  // namespace organsim
