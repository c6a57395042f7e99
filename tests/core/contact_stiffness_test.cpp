// The tool's local contact stiffness K = dF/dc (core/sim/contact_stiffness.h,
// force_law::push_penalty_center_jacobian): equal to central differences of
// the penalty and of the reference reaction with the tissue held.
//
// Tolerance: with h = 1e-7 m the central difference's truncation error,
// h^2/6 times the penalty's third derivative (~ k R / d^3), is below 1e-8 k
// for the distances here, and its rounding error about eps |f| / h ~ 1e-8 k;
// 1e-6 k leaves room and is far below the smallest entries compared (~k/10).
#include <gtest/gtest.h>

#include <iostream>
#include <random>
#include <stdexcept>

#include "core/physics/force_law.h"
#include "core/sim/contact_stiffness.h"
#include "core/sim/reference_forces.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace contact_stiffness_test {
namespace {

namespace fl = force_law;

constexpr double kH = 1e-7;   // m, central difference step
constexpr double kK = 500;    // N/m
constexpr double kR = 0.01;   // m

// Central differences of g(c) (a vector) in c: column j is dg/dc_j.
template <class G>
Mat3 central_differences(const Vec3& c, G g) {
  Mat3 d;
  for (int j = 0; j < 3; ++j) {
    Vec3 e = Vec3::Zero();
    e[j] = kH;
    d.col(j) = (g(c + e) - g(c - e)) / (2 * kH);
  }
  return d;
}

void expect_close(const Mat3& a, const Mat3& b, double tol) {
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), tol) << "analytic\n" << a << "\nfinite differences\n" << b;
}

TEST(ContactStiffness, PointPenaltyJacobianIsTheCentralDifferenceOfThePenalty) {
  const Vec3 x(0.003, -0.002, 0.004);  // the point, held
  const Vec3 c(0.0002, 0.0001, -0.0003);
  const auto f = [&](const Vec3& centre) {
    Vec3 out = Vec3::Zero();
    fl::push_penalty(Vec3(x - centre), kR, kK, out);
    return out;
  };
  const Vec3 o = x - c;
  const Mat3 j = fl::push_penalty_center_jacobian(Vec3(o / o.norm()), o.norm(), kR, kK, Mat3::Zero().eval());
  expect_close(j, central_differences(c, f), 1e-6 * kK);
  EXPECT_GT(j.cwiseAbs().maxCoeff(), 0.1 * kK);
}

TEST(ContactStiffness, TrianglePenaltyJacobianFollowsTheClosestFaceEdgeOrVertex) {
  const Vec3 x0(0, 0, 0), x1(0.01, 0.001, 0.0005), x2(0.002, 0.012, -0.001);
  const double share[3] = {0.4, 0.3, 0.5};
  const auto f = [&](const Vec3& centre) {
    Vec3 out = Vec3::Zero();
    double w[3];
    fl::sphere_triangle_penalty(centre, kR, x0, x1, x2, kK, share, out, w);
    return out;
  };
  // Above the face, beside the edge x0-x1, beyond the vertex x0: each 4-7 mm away.
  std::vector<int> regions;
  for (const Vec3& c : {Vec3(0.003, 0.003, 0.006), Vec3(0.005, -0.004, 0.003), Vec3(-0.003, -0.002, 0.004)}) {
    SCOPED_TRACE(c.transpose());
    double w[3];
    Vec3 force;
    ASSERT_TRUE(fl::sphere_triangle_penalty(c, kR, x0, x1, x2, kK, share, force, w));
    const Vec3 q = w[0] * x0 + w[1] * x1 + w[2] * x2;
    const double kt = kK * fl::triangle_penalty_scale(share);
    Mat3 follow = Mat3::Zero();
    int on = 0;
    for (double wi : w) on += wi > 0;
    regions.push_back(on);
    if (on == 3) {
      const Vec3 m = (x1 - x0).cross(x2 - x0).normalized();
      follow = Mat3::Identity() - m * m.transpose();
    } else if (on == 2) {
      const Vec3 e = (x1 - x0).normalized();  // the only edge these centres reach
      follow = e * e.transpose();
    }
    const Vec3 o = q - c;
    const Mat3 j = fl::push_penalty_center_jacobian(Vec3(o / o.norm()), o.norm(), kR, kt, follow);
    expect_close(j, central_differences(c, f), 1e-6 * kK);
  }
  EXPECT_EQ(regions, (std::vector<int>{3, 2, 1})) << "face, edge and vertex each once";
}

// A 4 cm box with its positions moved off the rest state (the tissue as the
// run left it), a sphere pressing into its top near a corner of the cells.
struct Pressed {
  Model model;
  std::vector<Vec3> x;
  Vec3 center;
};

Pressed pressed_box() {
  Material material;
  material.young_modulus = 4000;
  Pressed p{build_model(testing::jittered_box(4, 0.04, 0.2, 3), material, testing::fixed_bottom_options()), {},
            Vec3(0.0213, 0.0187, 0.0475)};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-4e-4, 4e-4);
  for (const Vec3& r : p.model.rest_position) p.x.push_back(r + Vec3(u(rng), u(rng), u(rng)));
  return p;
}

TEST(ContactStiffness, SurfaceContactStiffnessIsTheCentralDifferenceOfTheReactionWithTheTissueHeld) {
  const Pressed p = pressed_box();
  const auto reaction = [&](const Vec3& c) {
    std::vector<Vec3> force(p.x.size(), Vec3::Zero());
    return reference_surface_forces(p.model, p.x, c, kR, kK, force).force;
  };
  std::vector<Vec3> force(p.x.size(), Vec3::Zero());
  ASSERT_GT(reference_surface_forces(p.model, p.x, p.center, kR, kK, force).contacts, 3);
  const Mat3 k = reference_surface_stiffness(p.model, p.x, p.center, kR, kK);
  expect_close(k, central_differences(p.center, reaction), 1e-6 * kK);
  EXPECT_LT(k(2, 2), -0.1 * kK) << "pressing deeper pushes back harder";
  BackendTool tool{true, ToolMode::Push, kR, kK, ToolContact::Surface};
  EXPECT_EQ(tool_contact_stiffness(p.model, p.x, tool, p.center), k);
}

// With the sub-cell Hertz layer the reply's K is that of the layered
// reaction (reference_surface_forces with the layer, over the whole
// surface; here with h ten times the function's, so the two differences do
// not coincide), softer along the push than the layer-less contact's.
// Tolerance: the layer's terms are smooth while the touching set holds;
// 1e-5 k covers the differences' truncation at h = 1e-6 m, and a K that
// left the layer out is off by 40 % of k_zz.
TEST(ContactStiffness, WithTheHertzLayerItIsTheCentralDifferenceOfTheLayeredReaction) {
  Pressed p = pressed_box();
  // 1.2 mm deep: the layer's offset still rises with the force there (it is
  // held beyond a contact radius of R / 2, where K is the layer-less one).
  p.center.z() = 0.0488;
  const ContactLayer layer = contact_layer(p.model);
  const auto reaction = [&](const Vec3& c) {
    std::vector<Vec3> force(p.x.size(), Vec3::Zero());
    return reference_surface_forces(p.model, p.x, c, kR, kK, force, &layer).force;
  };
  BackendTool tool{true, ToolMode::Push, kR, kK, ToolContact::Surface};
  tool.hertz_layer = true;
  const Mat3 k = tool_contact_stiffness(p.model, p.x, tool, p.center, &layer);
  Mat3 fd;
  for (int j = 0; j < 3; ++j) {
    Vec3 step = Vec3::Zero();
    step[j] = 1e-6;
    fd.col(j) = (reaction(p.center + step) - reaction(p.center - step)) / 2e-6;
  }
  expect_close(k, fd, 1e-5 * kK);
  const Mat3 rigid = reference_surface_stiffness(p.model, p.x, p.center, kR, kK);
  std::cout << "k_zz with the Hertz layer " << k(2, 2) << " N/m, without " << rigid(2, 2) << " N/m\n";
  EXPECT_LT(k(2, 2), 0) << "pressing deeper still pushes back harder";
  EXPECT_GT(k(2, 2), 0.9 * rigid(2, 2)) << "but softer than without the layer";
  EXPECT_THROW(tool_contact_stiffness(p.model, p.x, tool, p.center), std::logic_error);
}

TEST(ContactStiffness, PointContactStiffnessIsTheCentralDifferenceOfTheReactionWithTheTissueHeld) {
  Pressed p = pressed_box();
  p.center.z() = 0.042;  // 8 mm into the top: point contact needs the points inside the sphere
  const auto reaction = [&](const Vec3& c) {
    std::vector<Vec3> force(p.x.size(), Vec3::Zero());
    return reference_push_forces(p.x, c, kR, kK, force, p.model.tool_k_scale).force;
  };
  std::vector<Vec3> force(p.x.size(), Vec3::Zero());
  ASSERT_GT(reference_push_forces(p.x, p.center, kR, kK, force, p.model.tool_k_scale).contacts, 1);
  const Mat3 k = reference_push_stiffness(p.x, p.center, kR, kK, p.model.tool_k_scale);
  expect_close(k, central_differences(p.center, reaction), 1e-6 * kK);
  BackendTool tool{true, ToolMode::Push, kR, kK, ToolContact::Points};
  EXPECT_EQ(tool_contact_stiffness(p.model, p.x, tool, p.center), k);
  tool.mode = ToolMode::Pull;
  EXPECT_EQ(tool_contact_stiffness(p.model, p.x, tool, p.center), Mat3::Zero());
}

// A pulling tool's attachment springs: K = -sum k s_i I, the central
// difference of the pull reaction with the tissue held.
TEST(ContactStiffness, HeldPointsStiffnessIsTheCentralDifferenceOfThePullReaction) {
  const Pressed p = pressed_box();
  Attachment held;
  for (int32_t i = 0; i < p.model.npoint(); ++i)
    if ((p.x[i] - p.center).norm() < 0.02) {
      held.points.push_back(i);
      held.offsets.push_back(p.model.rest_position[i] - p.center);
    }
  ASSERT_GT(held.points.size(), 3u);
  const auto reaction = [&](const Vec3& c) {
    std::vector<Vec3> force(p.x.size(), Vec3::Zero());
    return reference_pull_forces(p.x, held, c, kK, force, p.model.tool_k_scale).force;
  };
  const Mat3 k = attachment_stiffness(p.model, held, kK);
  expect_close(k, central_differences(p.center, reaction), 1e-6 * kK);
  EXPECT_LT(k(0, 0), -kK) << "several points held: stiffer than one spring";
}

}  // namespace
}  // namespace contact_stiffness_test
}  // namespace organsim
