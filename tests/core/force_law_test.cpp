// core/physics/force_law.h: each element's force is minus the gradient of
// its energy (central differences), and the suture and tool rules hold at
// their edges. The reference and every kernel evaluate these functions, so
// what is checked here holds for all of them.
#include <gtest/gtest.h>

#include <random>

#include "core/physics/force_law.h"
#include "core/util/vec.h"

namespace organsim {
namespace {

namespace fl = force_law;

// Central differences with h = 1e-6 of the lengths involved (cm scale): the
// truncation error is O(h^2) ~ 1e-12 relative, rounding ~1e-16 / h ~ 1e-10;
// 1e-7 of the force's scale leaves room for both.
constexpr double kH = 1e-8, kTol = 1e-7;

double spring_energy_at(const Vec3& a, const Vec3& b, double k, double rest) {
  return fl::spring_energy(k, (b - a).norm(), rest);
}

TEST(ForceLaw, SpringForceIsMinusTheEnergyGradient) {
  const Vec3 a(0.01, 0.002, -0.003), b(0.025, 0.011, 0.004);
  const double k = 37, rest = 0.012;
  const double length = (b - a).norm();
  const Vec3 u = (b - a) / length;
  const Vec3 on_a = fl::spring_tension(k, 0.0, length, rest, 0.0) * u;  // no damper: elastic force
  for (int c = 0; c < 3; ++c) {
    Vec3 ap = a, am = a;
    ap[c] += kH, am[c] -= kH;
    const double gradient = (spring_energy_at(ap, b, k, rest) - spring_energy_at(am, b, k, rest)) / (2 * kH);
    EXPECT_NEAR(on_a[c], -gradient, kTol * on_a.norm()) << c;
  }
  // The damper adds d times the closing rate; a stretched spring pulls.
  EXPECT_DOUBLE_EQ(fl::spring_tension(k, 2.0, length, rest, -0.5), k * (length - rest) - 1.0);
  EXPECT_GT(fl::spring_tension(k, 0.0, length, rest, 0.0), 0.0);
}

TEST(ForceLaw, SutureOnlyPulls) {
  EXPECT_EQ(fl::suture_tension(5.0, 0.010, 0.012), 0.0);   // slack
  EXPECT_EQ(fl::suture_tension(-5.0, 0.014, 0.012), 0.0);  // stretched, but closing fast: no push
  EXPECT_EQ(fl::suture_tension(5.0, 0.014, 0.012), 5.0);
  EXPECT_EQ(fl::suture_energy(10.0, 0.010, 0.012), 0.0);
  EXPECT_DOUBLE_EQ(fl::suture_energy(10.0, 0.014, 0.012), fl::spring_energy(10.0, 0.014, 0.012));
}

TEST(ForceLaw, VolumeForceIsMinusTheEnergyGradient) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.002, 0.002);
  const Vec3 x0(0, 0, 0), x1 = Vec3(0.01, 0, 0) + Vec3(u(rng), u(rng), u(rng)),
             x2 = Vec3(0, 0.01, 0) + Vec3(u(rng), u(rng), u(rng)), x3 = Vec3(0, 0, 0.01) + Vec3(u(rng), u(rng), u(rng));
  const double k = 3e9, rest = 1.0e-7;  // N/m^5, m^3: V is about 1.7e-7
  auto energy = [&](const Vec3& p1) { return fl::volume_energy(k, fl::tet_volume6(Vec3(p1 - x0), Vec3(x2 - x0), Vec3(x3 - x0)) / 6, rest); };
  const Vec3 e1 = x1 - x0, e2 = x2 - x0, e3 = x3 - x0;
  Vec3 g1, g2, g3;
  fl::tet_volume_gradients6(e1, e2, e3, g1, g2, g3);
  const double p = fl::volume_pressure(k, fl::tet_volume6(e1, e2, e3) / 6, rest);
  const Vec3 f1 = -p * g1 / 6;
  for (int c = 0; c < 3; ++c) {
    Vec3 plus = x1, minus = x1;
    plus[c] += kH * 0.01, minus[c] -= kH * 0.01;
    const double gradient = (energy(plus) - energy(minus)) / (2 * kH * 0.01);
    EXPECT_NEAR(f1[c], -gradient, kTol * f1.norm()) << c;
  }
  // The nodal form's tet pressure is the corners' mean.
  EXPECT_DOUBLE_EQ(fl::tet_pressure_from_nodal(1.0, 2.0, 3.0, 6.0), 3.0);
}

TEST(ForceLaw, PushPenaltyIsMinusTheEnergyGradientAndZeroOutside) {
  const double k = 200, radius = 0.01;
  const Vec3 offset(0.003, -0.004, 0.002);
  Vec3 f;
  ASSERT_TRUE(fl::push_penalty(offset, radius, k, f));
  for (int c = 0; c < 3; ++c) {
    Vec3 plus = offset, minus = offset;
    plus[c] += kH, minus[c] -= kH;
    const double gradient =
        (fl::push_penalty_energy(k, radius, plus.norm()) - fl::push_penalty_energy(k, radius, minus.norm())) / (2 * kH);
    EXPECT_NEAR(f[c], -gradient, kTol * f.norm()) << c;
  }
  Vec3 untouched(7, 7, 7);
  EXPECT_FALSE(fl::push_penalty(Vec3(0.0, 0.0, radius), radius, k, untouched));  // on the surface: no contact
  EXPECT_EQ(untouched, Vec3(7, 7, 7));
  ASSERT_TRUE(fl::push_penalty(Vec3(0.0, 0.0, 0.0), radius, k, f));  // at the centre: along +z
  EXPECT_EQ(f, Vec3(0, 0, k * radius));
  EXPECT_EQ(fl::pull_attachment(Vec3(1, 2, 3), Vec3(1, 1, 1), 4.0), Vec3(0, 4, 8));
}

TEST(ForceLaw, ShearBarrierSlopeIsTheBarriersDerivative) {
  for (const double J : {0.2, 0.49, 0.51, 0.9, 1.0, 1.7}) {
    const double h = 1e-6;
    const double derivative = (fl::shear_barrier(J + h) - fl::shear_barrier(J - h)) / (2 * h);
    EXPECT_NEAR(fl::shear_barrier_slope(J), derivative, 1e-7) << J;
  }
}

// The rest stiffness blocks are the derivative of the forces at rest:
// K_ij = -df_i/dx_j by central differences of each law at a rest state
// (a spring at its rest length, a tet at its rest volume, F = I). The
// forces are linear there to O(h^2): 1e-7 of the block's scale as above.
TEST(ForceLaw, RestStiffnessIsMinusTheForcesDerivativeAtRest) {
  const Vec3 a(0.01, 0.002, -0.003), b(0.025, 0.011, 0.004);
  const double k = 37, rest = (b - a).norm();
  auto spring_force_on_a = [&](const Vec3& pb) {
    const double length = (pb - a).norm();
    return Vec3(fl::spring_tension(k, 0.0, length, rest, 0.0) * (pb - a) / length);
  };
  const Eigen::Matrix3d K_spring = fl::spring_rest_stiffness(k, Vec3((b - a) / rest));
  for (int c = 0; c < 3; ++c) {
    Vec3 plus = b, minus = b;
    plus[c] += kH, minus[c] -= kH;
    const Vec3 dfa = (spring_force_on_a(plus) - spring_force_on_a(minus)) / (2 * kH);
    EXPECT_LT((-dfa - Eigen::Vector3d(-K_spring.col(c))).norm(), kTol * K_spring.norm()) << c;  // K_ab = -K_aa
  }

  const Vec3 x0(0, 0, 0), x1(0.011, 0.001, 0), x2(0.002, 0.01, 0.001), x3(0.001, -0.001, 0.012);
  const double kv = 3e9, v_rest = fl::tet_volume6(Vec3(x1 - x0), Vec3(x2 - x0), Vec3(x3 - x0)) / 6;
  auto volume_force_on_1 = [&](const Vec3& p2) {
    const Vec3 e1 = x1 - x0, e2 = p2 - x0, e3 = x3 - x0;
    Vec3 g1, g2, g3;
    fl::tet_volume_gradients6(e1, e2, e3, g1, g2, g3);
    return Vec3(-fl::volume_pressure(kv, fl::tet_volume6(e1, e2, e3) / 6, v_rest) * g1 / 6);
  };
  Vec3 g1, g2, g3;
  fl::tet_volume_gradients6(Vec3(x1 - x0), Vec3(x2 - x0), Vec3(x3 - x0), g1, g2, g3);
  const Eigen::Matrix3d K_volume = fl::volume_rest_stiffness(kv, Vec3(g1 / 6), Vec3(g2 / 6));
  const double h = kH * 0.01;
  for (int c = 0; c < 3; ++c) {
    Vec3 plus = x2, minus = x2;
    plus[c] += h, minus[c] -= h;
    const Vec3 df = (volume_force_on_1(plus) - volume_force_on_1(minus)) / (2 * h);
    EXPECT_LT((-df - Eigen::Vector3d(K_volume.col(c))).norm(), kTol * K_volume.norm()) << c;
  }

  // Shear element per unit k: f_i = -P(F) g_i with F = I + sum_j u_j g_j^T.
  const Vec3 gi(31.0, -4.0, 12.0), gj(-7.0, 22.0, 5.0);  // 1/m, gradients of a cm-sized tet
  const Eigen::Matrix3d K_shear = fl::shear_rest_stiffness(gi, gj);
  for (int c = 0; c < 3; ++c) {
    Eigen::Matrix3d dF = Eigen::Matrix3d::Zero();
    dF.row(c) = gj.transpose() * 1e-6;  // u_j = 1e-6 e_c
    const Vec3 df = (-fl::shear_stress(Eigen::Matrix3d(Eigen::Matrix3d::Identity() + dF)) * gi +
                     fl::shear_stress(Eigen::Matrix3d(Eigen::Matrix3d::Identity() - dF)) * gi) / 2e-6;
    EXPECT_LT((-df - Eigen::Vector3d(K_shear.col(c))).norm(), 1e-6 * K_shear.norm()) << c;
  }
}

}  // namespace
}  // namespace organsim

