// core/physics/force_law.h: each element's force is minus the gradient of
// its energy (central differences), and the suture and tool rules hold at
// their edges. The reference and every kernel evaluate these functions, so
// what is checked here holds for all of them.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <string>

#include "core/physics/force_law.h"
#include "core/util/vec.h"

namespace organsim {
namespace force_law_test {
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

// --- The triangle penalties (sphere and capsule on a surface triangle) ---------
// docs/physics.md ("Tool"): a triangle t inside the tool carries the
// penalty k_t (R - d) along n_t, d the distance from the sphere's centre
// (or the capsule's segment) to the triangle, and is spread to the corners
// by the closest point's weights; the force is minus the gradient of
//   E_t = k_t/2 (R - d)^2,  k_t = k min_i share_i.
// The energy below is written from that formula with a distance computed
// here by other means than force_law's (the plane's foot from the Gram
// system and the edges' clamped projections, not the Voronoi regions; a
// segment pair by its quadratic's interior point and the square's four
// edges, not Ericson's clamping), so a wrong law, distance or weights in
// force_law.h show here although the reference and every kernel call it.

// Closest point of the segment u-v to p, by the clamped projection.
Vec3 closest_on_segment(const Vec3& p, const Vec3& u, const Vec3& v) {
  const Vec3 e = v - u;
  const double t = std::clamp(e.dot(p - u) / e.squaredNorm(), 0.0, 1.0);
  return u + t * e;
}

// Distance from p to the triangle: the plane's foot if its barycentric
// coordinates (from the 2x2 Gram system) are all non-negative, else the
// nearest of the three edges.
double point_triangle_distance(const Vec3& p, const Vec3& x0, const Vec3& x1, const Vec3& x2) {
  const Vec3 e1 = x1 - x0, e2 = x2 - x0, r = p - x0;
  const double a11 = e1.dot(e1), a12 = e1.dot(e2), a22 = e2.dot(e2);
  const double b1 = e1.dot(r), b2 = e2.dot(r), det = a11 * a22 - a12 * a12;
  const double s = (a22 * b1 - a12 * b2) / det, t = (a11 * b2 - a12 * b1) / det;
  if (s >= 0 && t >= 0 && s + t <= 1) return (x0 + s * e1 + t * e2 - p).norm();
  return std::min({(closest_on_segment(p, x0, x1) - p).norm(), (closest_on_segment(p, x1, x2) - p).norm(),
                   (closest_on_segment(p, x2, x0) - p).norm()});
}

// Distance between the segments p1-q1 and p2-q2: the minimum of the convex
// quadratic |p1 + s d1 - p2 - t d2|^2 over [0, 1]^2, at its stationary point
// if that lies inside, else on one of the square's four edges.
double segment_segment_distance(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.dot(d1), b = d1.dot(d2), e = d2.dot(d2), c = d1.dot(r), f = d2.dot(r);
  const double det = a * e - b * b;
  double best = std::min({(closest_on_segment(p1, p2, q2) - p1).norm(), (closest_on_segment(q1, p2, q2) - q1).norm(),
                          (closest_on_segment(p2, p1, q1) - p2).norm(), (closest_on_segment(q2, p1, q1) - q2).norm()});
  if (det > 1e-12 * a * e) {
    const double s = (b * f - c * e) / det, t = (a * f - b * c) / det;
    if (s > 0 && s < 1 && t > 0 && t < 1) best = std::min(best, (r + s * d1 - t * d2).norm());
  }
  return best;
}

// Distance from the segment a-b to the triangle when the segment does not
// pass through it: the nearest of its ends to the triangle and of the
// segment to the triangle's edges (the distance to the plane is linear
// along the segment, so an interior point can be nearest only over an edge).
double segment_triangle_distance(const Vec3& a, const Vec3& b, const Vec3& x0, const Vec3& x1, const Vec3& x2) {
  return std::min({point_triangle_distance(a, x0, x1, x2), point_triangle_distance(b, x0, x1, x2),
                   segment_segment_distance(a, b, x0, x1), segment_segment_distance(a, b, x1, x2),
                   segment_segment_distance(a, b, x2, x0)});
}

// The penalty's energy at distance d (0 outside the tool).
double triangle_penalty_energy(double k_t, double radius, double d) {
  return d < radius ? k_t / 2 * (radius - d) * (radius - d) : 0.0;
}

// Central differences at h = 1e-7 m on cm-sized triangles with the tool
// 0.2-0.9 R (R = 1 cm) from them: the energy's third derivative is about
// k_t (R / d^2 + 3 / d) <= 4e3 k_t / m, so the truncation error h^2 / 6
// times it is ~7e-12 k_t N against a force k_t (R - d) >= 1e-3 k_t N, and
// rounding eps E / h ~ 1e-14 k_t N: 1e-6 of the force leaves a factor over
// 100 above both. (A step straddling a boundary between the closest
// point's regions, where the distance's second derivative jumps, would err
// by up to h k_t (R - d) / d, ~1e-5 relative; for that a configuration
// would have to lie within 1e-7 m of the boundary, which these seeds do not.)
constexpr double kPenaltyH = 1e-7, kPenaltyTol = 1e-6;
constexpr double kPenaltyK = 500, kPenaltyRadius = 0.01;
// The corners' shares; k_t = k times the smallest, 0.2 (stated here, not
// taken from force_law::triangle_penalty_scale).
constexpr double kShare[3] = {0.3, 0.2, 0.25};
constexpr double kPenaltyKt = kPenaltyK * 0.2;

// A random cm-sized triangle near the plane z = 0, counter-clockwise seen
// from +z (the outside), its corners moved by up to 3 mm on every axis.
std::array<Vec3, 3> random_triangle(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-0.003, 0.003);
  return {Vec3(u(rng), u(rng), u(rng)), Vec3(0.012 + u(rng), 0.001 + u(rng), u(rng)),
          Vec3(0.004 + u(rng), 0.011 + u(rng), u(rng))};
}

// Which feature of the triangle the closest point lies on, from its weights:
// 3 (face), 2 (an edge) or 1 (a vertex) non-zero weights.
int feature(const double w[3]) { return (w[0] > 0) + (w[1] > 0) + (w[2] > 0); }

// The law's force on every corner (w_i f) and on the tool (-f, the tool
// translated as a whole: both ends of a capsule) against minus the central
// differences of energy(corners, tool shift).
template <class Energy>
void expect_corner_and_tool_forces(const std::array<Vec3, 3>& x, const Vec3& f, const double w[3], Energy energy,
                                   const std::string& where) {
  const double tol = kPenaltyTol * f.norm();
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 3; ++c) {
      std::array<Vec3, 3> plus = x, minus = x;
      plus[i][c] += kPenaltyH, minus[i][c] -= kPenaltyH;
      const double gradient = (energy(plus, Vec3::Zero()) - energy(minus, Vec3::Zero())) / (2 * kPenaltyH);
      EXPECT_NEAR(w[i] * f[c], -gradient, tol) << where << ", corner " << i << ", axis " << c;
    }
  for (int c = 0; c < 3; ++c) {
    const Vec3 shift = kPenaltyH * Vec3::Unit(c);
    const double gradient = (energy(x, shift) - energy(x, Vec3(-shift))) / (2 * kPenaltyH);
    EXPECT_NEAR(-f[c], -gradient, tol) << where << ", tool, axis " << c;
  }
}

TEST(ForceLaw, SphereTrianglePenaltyIsMinusTheEnergyGradientOnFaceEdgesAndVertices) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> across(-0.008, 0.022), height(-0.004, 0.012);
  int found[4] = {0, 0, 0, 0}, tries = 0;
  while ((found[1] < 4 || found[2] < 4 || found[3] < 4) && ++tries < 100000) {
    const std::array<Vec3, 3> x = random_triangle(rng);
    const Vec3 center(across(rng), across(rng), height(rng));
    const double d = point_triangle_distance(center, x[0], x[1], x[2]);
    if (!(d > 0.2 * kPenaltyRadius && d < 0.9 * kPenaltyRadius)) continue;
    Vec3 f;
    double w[3];
    ASSERT_TRUE(fl::sphere_triangle_penalty(center, kPenaltyRadius, x[0], x[1], x[2], kPenaltyK, kShare, f, w));
    const int kind = feature(w);
    if (found[kind] >= 4) continue;
    ++found[kind];
    // Its size is the law's at the distance found here (1e-12 N: rounding).
    EXPECT_NEAR(f.norm(), kPenaltyKt * (kPenaltyRadius - d), 1e-12) << "feature " << kind;
    auto energy = [&](const std::array<Vec3, 3>& p, const Vec3& shift) {
      return triangle_penalty_energy(kPenaltyKt, kPenaltyRadius,
                                     point_triangle_distance(Vec3(center + shift), p[0], p[1], p[2]));
    };
    expect_corner_and_tool_forces(x, f, w, energy, "sphere, feature " + std::to_string(kind));
  }
  EXPECT_EQ(found[1], 4) << "vertex cases";
  EXPECT_EQ(found[2], 4) << "edge cases";
  EXPECT_EQ(found[3], 4) << "face cases";
  // Outside the sphere: no force, nothing written.
  const std::array<Vec3, 3> x = random_triangle(rng);
  Vec3 untouched(7, 7, 7);
  double w[3] = {7, 7, 7};
  EXPECT_FALSE(fl::sphere_triangle_penalty(Vec3(0.005, 0.004, 0.02), kPenaltyRadius, x[0], x[1], x[2], kPenaltyK,
                                           kShare, untouched, w));
  EXPECT_EQ(untouched, Vec3(7, 7, 7));
}

// The capsule against a triangle, its segment not through it (the crossing
// branch pushes with k_t R along the normal, the limit of the sphere's rule,
// and is not the gradient of an energy: docs/physics.md). The corners' and
// the tool's forces are minus the energy's gradient, and so is the torque on
// the tool about the segment's midpoint m, (q - m) x (-f) with q the
// triangle's closest point by the law's weights, by central differences of
// small rotations of the segment about m: that checks the point where the
// force acts, which a translation does not see.
TEST(ForceLaw, CapsuleTrianglePenaltyIsMinusTheEnergyGradientOnFaceEdgesAndVertices) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> across(-0.008, 0.022), height(-0.004, 0.012), unit(-1, 1),
      length(0.01, 0.04);
  int found[4] = {0, 0, 0, 0}, interior = 0, tries = 0;
  while ((found[1] < 4 || found[2] < 4 || found[3] < 4 || interior < 4) && ++tries < 200000) {
    const std::array<Vec3, 3> x = random_triangle(rng);
    const Vec3 mid(across(rng), across(rng), height(rng));
    Vec3 axis(unit(rng), unit(rng), unit(rng));
    if (axis.norm() < 0.1) continue;
    axis = axis.normalized() * length(rng) / 2;
    const Vec3 a = mid - axis, b = mid + axis;
    bool crossing = false;
    const Vec3 p = fl::segment_point_closest_to_triangle(a, b, x[0], x[1], x[2], crossing);
    if (crossing) continue;
    const double d = segment_triangle_distance(a, b, x[0], x[1], x[2]);
    if (!(d > 0.2 * kPenaltyRadius && d < 0.9 * kPenaltyRadius)) continue;
    Vec3 f;
    double w[3];
    ASSERT_TRUE(fl::capsule_triangle_penalty(a, b, kPenaltyRadius, x[0], x[1], x[2], kPenaltyK, kShare, f, w));
    const int kind = feature(w);
    const bool inside = (p - a).norm() > 1e-4 && (p - b).norm() > 1e-4;  // nearest at the segment's interior
    if (found[kind] >= 4 && (!inside || interior >= 4)) continue;
    ++found[kind];
    interior += inside;
    EXPECT_NEAR(f.norm(), kPenaltyKt * (kPenaltyRadius - d), 1e-12) << "feature " << kind;
    auto energy = [&](const std::array<Vec3, 3>& q, const Vec3& shift) {
      return triangle_penalty_energy(kPenaltyKt, kPenaltyRadius,
                                     segment_triangle_distance(Vec3(a + shift), Vec3(b + shift), q[0], q[1], q[2]));
    };
    const std::string where = "capsule, feature " + std::to_string(kind) + (inside ? ", segment interior" : ", end");
    expect_corner_and_tool_forces(x, f, w, energy, where);
    const Vec3 q = w[0] * x[0] + w[1] * x[1] + w[2] * x[2];
    const Vec3 torque = (q - mid).cross(Vec3(-f));
    // An angle step of h / |axis| moves the ends by h; the torque's scale is
    // |f| times its lever, the larger of |q - m| and the half-length.
    const double h = kPenaltyH / axis.norm(), tol = kPenaltyTol * f.norm() * std::max((q - mid).norm(), axis.norm());
    for (int c = 0; c < 3; ++c) {
      auto rotated = [&](double angle) {
        const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, Vec3::Unit(c)).toRotationMatrix();
        return triangle_penalty_energy(
            kPenaltyKt, kPenaltyRadius,
            segment_triangle_distance(Vec3(mid - r * axis), Vec3(mid + r * axis), x[0], x[1], x[2]));
      };
      EXPECT_NEAR(torque[c], -(rotated(h) - rotated(-h)) / (2 * h), tol) << where << ", torque, axis " << c;
    }
  }
  EXPECT_GE(found[1], 4) << "vertex cases";
  EXPECT_GE(found[2], 4) << "edge cases";
  EXPECT_GE(found[3], 4) << "face cases";
  EXPECT_GE(interior, 4) << "cases with the segment's interior nearest";
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
}  // namespace force_law_test
}  // namespace organsim

