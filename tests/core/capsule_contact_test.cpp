// The capsule tool (force_law::capsule_triangle_penalty and the points
// contact from its segment): its closest points, continuity across triangle
// edges, its reaction and torque about the tool's origin, what the CPU
// kernels apply against the double reference, the stiffness bound dt_crit
// counts, and a sphere that ignores the tool's orientation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/physics/force_law.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/reference_forces.h"
#include "tests/core/contact_test_util.h"

namespace organsim {
namespace capsule_contact_test {
namespace {

using testing::Contact;
using testing::largest_change;

constexpr double kSize = testing::kContactBox;
constexpr double kK = testing::kContactK;

Model box(int cells) { return testing::contact_box(cells); }

// A capsule of `radius` whose tip (end a) is the tool's origin, with a 3 cm
// shaft along the frame's +x.
BackendTool capsule(double radius, ToolContact contact = ToolContact::Surface) {
  BackendTool t{true, ToolMode::Push, radius, kK, contact};
  t.shape = ToolShape::Capsule;
  t.end_b = Vec3(0.03, 0, 0);
  return t;
}
// The frame turned so that the shaft rises at `tilt` radians from the
// horizontal, heading `heading` radians about z.
Quat pose(double tilt, double heading) {
  return Quat(Eigen::AngleAxisd(heading, Vec3::UnitZ())) * Quat(Eigen::AngleAxisd(-tilt, Vec3::UnitY()));
}

Contact at_rest(const Model& m, const BackendTool& tool, const Vec3& origin, const Quat& turn,
                const std::vector<Vec3>* x = nullptr) {
  Contact c;
  c.force.assign(m.npoint(), Vec3::Zero());
  const ToolPlacement placed = place_tool(tool, origin, turn);
  const std::vector<Vec3>& at = x ? *x : m.rest_position;
  c.reaction = tool.contact == ToolContact::Surface
                   ? reference_surface_forces(m, at, placed, kK, c.force)
                   : reference_push_forces(at, placed, kK, c.force, m.tool_k_scale);
  return c;
}

// The segment's point closest to a triangle against a brute-force search:
// the distance from a + s (b - a) to the triangle is convex in s, so a
// ternary search finds its minimum to round-off. Random segments and
// triangles: crossing, parallel-ish, beside an edge, beyond a vertex.
TEST(CapsuleContact, SegmentPointClosestToTheTriangleMatchesABruteForceSearch) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  auto distance = [](const Vec3& p, const Vec3& x0, const Vec3& x1, const Vec3& x2) {
    double w[3];
    force_law::triangle_closest_weights(p, x0, x1, x2, w);
    return (w[0] * x0 + w[1] * x1 + w[2] * x2 - p).norm();
  };
  int crossings = 0, interior = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 x0(u(rng), u(rng), 0.2 * u(rng)), x1(u(rng), u(rng), 0.2 * u(rng)), x2(u(rng), u(rng), 0.2 * u(rng));
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    bool crossing = false;
    const Vec3 p = force_law::segment_point_closest_to_triangle(a, b, x0, x1, x2, crossing);
    double lo = 0, hi = 1;
    for (int i = 0; i < 200; ++i) {
      const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
      if (distance(a + m1 * (b - a), x0, x1, x2) < distance(a + m2 * (b - a), x0, x1, x2)) hi = m2; else lo = m1;
    }
    const double best = distance(a + 0.5 * (lo + hi) * (b - a), x0, x1, x2);
    const double got = distance(p, x0, x1, x2);
    // p lies on the segment (to round-off) and is as close as the search's minimum.
    EXPECT_LT((p - a).cross(b - a).norm(), 1e-12) << "trial " << trial;
    EXPECT_LT(got, best + 1e-9) << "trial " << trial;
    if (crossing) {
      ++crossings;
      EXPECT_LT(got, 1e-12) << "trial " << trial;
    }
    const double s = (p - a).dot(b - a) / (b - a).squaredNorm();
    interior += s > 1e-6 && s < 1 - 1e-6;
  }
  // Both kinds of answers occur: through the triangle, and inside the segment (not only its ends).
  EXPECT_GT(crossings, 20);
  EXPECT_GT(interior, 200);
}

// A finite-difference check as the sphere's (SurfaceContact test): the
// capsule's tip pressing at a top-face edge's midpoint, and its shaft lying
// 3 degrees from flat across an edge, moved by +-h across it, changes the
// total force, the torque about the origin and every point's force by
// O(k h); dropping or doubling a triangle at the edge would jump by about
// k * depth, a thousand times more.
TEST(CapsuleContact, ForceAndTorqueAreContinuousAcrossEdges) {
  const Model m = box(4);
  const double radius = 0.004, depth = 0.0015, h = 1e-7;
  const double bound = 20 * kK * h;
  const BackendTool tool = capsule(radius);
  int edges = 0;
  for (int32_t t = 0; t < m.nsurface(); ++t) {
    const Tri& tri = m.surface[t];
    const Vec3 a = m.rest_position[tri[0]], b = m.rest_position[tri[1]], c = m.rest_position[tri[2]];
    if (std::abs(a.z() - kSize) + std::abs(b.z() - kSize) + std::abs(c.z() - kSize) > 1e-12) continue;
    const Vec3 mid = 0.5 * (a + b), across = Vec3(0, 0, 1).cross(b - a).normalized();
    if (mid.x() < 0.3 * kSize || mid.x() > 0.7 * kSize || mid.y() < 0.3 * kSize || mid.y() > 0.7 * kSize) continue;
    const double heading = std::atan2(across.y(), across.x());
    // Tip on the edge, shaft rising at 45 degrees; and the shaft 3 degrees
    // from flat with its middle over the edge (the tip 0.8 mm lower).
    for (const double tilt : {0.785, 0.05}) {
      const Quat turn = pose(tilt, heading + 0.4);
      Vec3 origin = mid + Vec3(0, 0, radius - depth);
      if (tilt < 0.5) origin -= 0.5 * (turn * tool.end_b);
      const Contact minus = at_rest(m, tool, origin - h * across, turn), plus = at_rest(m, tool, origin + h * across, turn);
      ASSERT_GT(minus.reaction.force.norm(), 0.05 * kK * depth) << "the capsule must press on the edge";
      EXPECT_LT((plus.reaction.force - minus.reaction.force).norm(), bound) << "edge of triangle " << t;
      EXPECT_LT((plus.reaction.torque - minus.reaction.torque).norm(), bound * 0.03) << "edge of triangle " << t;
      EXPECT_LT(largest_change(plus, minus), bound) << "edge of triangle " << t;
      // Turning by a small angle about the origin is continuous too.
      const Quat turned = Quat(Eigen::AngleAxisd(h / 0.03, Vec3::UnitZ())) * turn;
      const Contact rotated = at_rest(m, tool, origin - h * across, turned);
      EXPECT_LT((rotated.reaction.force - minus.reaction.force).norm(), bound) << "edge of triangle " << t;
      EXPECT_LT((rotated.reaction.torque - minus.reaction.torque).norm(), bound * 0.03) << "edge of triangle " << t;
    }
    ++edges;
  }
  EXPECT_GT(edges, 4);
}

// The reaction is minus the sum of the forces applied, and its torque is
// about the tool's origin (here 1 cm behind the tip, on the shaft's line),
// not about the contact: exact to round-off, for the surface contact and
// the points contact.
TEST(CapsuleContact, ReactionIsMinusTheAppliedSumWithTheTorqueAboutTheOrigin) {
  const Model m = box(4);
  const Quat turn = pose(0.3, 0.7);
  for (const ToolContact contact : {ToolContact::Surface, ToolContact::Points}) {
    SCOPED_TRACE(contact == ToolContact::Surface ? "surface" : "points");
    BackendTool tool = capsule(0.006, contact);
    tool.end_a = Vec3(0.01, 0, 0), tool.end_b = Vec3(0.04, 0, 0);
    const Vec3 origin = Vec3(0.52 * kSize, 0.47 * kSize, kSize + 0.002) - turn * tool.end_a;
    const Contact c = at_rest(m, tool, origin, turn);
    Vec3 sum = Vec3::Zero(), torque = Vec3::Zero();
    for (int32_t i = 0; i < m.npoint(); ++i) {
      sum += c.force[i];
      torque += (m.rest_position[i] - origin).cross(c.force[i]);
    }
    ASSERT_GT(sum.norm(), 0.05 * kK * 0.002);
    // The contacts lie about 1 cm from the origin: a clear torque.
    ASSERT_GT(torque.norm(), 0.3 * sum.norm() * 0.01);
    EXPECT_LT((c.reaction.force + sum).norm(), 1e-12 * sum.norm());
    EXPECT_LT((c.reaction.torque + torque).norm(), 1e-12 * sum.norm() * 0.04);
  }
}

// The points contact: a point beside the shaft is pushed straight away
// from it by k (R - d), whichever part of the shaft it lies against, and a
// point beyond an end radially from that end.
TEST(CapsuleContact, PointsContactPushesAwayFromTheSegment) {
  BackendTool tool = capsule(0.005, ToolContact::Points);
  const ToolPlacement placed = place_tool(tool, Vec3(0.01, 0, 0), Quat::Identity());  // segment x in [0.01, 0.04]
  const std::vector<Vec3> x = {Vec3(0.025, 0.003, 0), Vec3(0.041, 0, 0.002), Vec3(0.025, 0.006, 0)};
  std::vector<Vec3> f(x.size(), Vec3::Zero());
  const Reaction r = reference_push_forces(x, placed, kK, f);
  EXPECT_EQ(r.contacts, 2);
  EXPECT_LT((f[0] - Vec3(0, kK * 0.002, 0)).norm(), 1e-12);
  const Vec3 off = Vec3(0.001, 0, 0.002);
  EXPECT_LT((f[1] - kK * (0.005 - off.norm()) * off.normalized()).norm(), 1e-12);
  EXPECT_EQ(f[2], Vec3::Zero());
  EXPECT_LT((r.torque - ((x[0] - placed.origin).cross(-f[0]) + (x[1] - placed.origin).cross(-f[1]))).norm(), 1e-15);
}

// What the CPU kernels apply: one substep from rest with the capsule
// pressed in, each point's contact force recovered from its motion (m (x' -
// x) / dt^2; no internal force at rest without gravity) against the
// reference's, on the kernel in double (to round-off) and float, surface
// and points.
TEST(CapsuleContact, CpuKernelsApplyTheReferenceForcesAndReportMinusTheirSum) {
  const Model m = box(4);
  const Vec3 origin(0.52 * kSize, 0.47 * kSize, kSize + 0.002);
  const Quat turn = pose(0.3, 0.7);
  const double dt = 1e-4;
  for (const ToolContact contact : {ToolContact::Surface, ToolContact::Points})
    for (const Precision precision : {Precision::Double, Precision::Float}) {
      const BackendTool tool = capsule(0.006, contact);
      auto backend = make_cpu_backend(m, tool, {precision, 1});
      SCOPED_TRACE(backend->device() + (contact == ToolContact::Surface ? ", surface" : ", points"));
      const Reaction got = backend->tick(testing::one_step_at(dt, origin, turn));
      const Contact want = at_rest(m, tool, origin, turn);
      const testing::Applied applied = testing::applied_in_one_step(m, *backend, dt, want.force);
      ASSERT_GT(applied.peak, 0.05);
      // Float: rest positions rounded to ~2e-9 m against penetrations of
      // ~2 mm, displacements held in float: ~1e-6 of the force; 1e-4.
      const double tol = precision == Precision::Double ? 1e-8 : 1e-4;
      EXPECT_LT(applied.worst, tol * applied.peak);
      EXPECT_EQ(got.contacts, want.reaction.contacts);
      const double rtol = precision == Precision::Double ? 1e-12 : 1e-5;
      EXPECT_LT((got.force - want.reaction.force).norm(), rtol * want.reaction.force.norm());
      EXPECT_LT((got.torque - want.reaction.torque).norm(), rtol * want.reaction.force.norm() * 0.03);
    }
}

// Every point's contact stiffness (the derivative of its own force along
// the normal) stays within k s_i, the bound dt_crit counts, wherever the
// capsule presses: its tip, and its shaft lying nearly flat over vertices,
// edges and faces.
TEST(CapsuleContact, StiffnessPerPointStaysWithinTheBoundDtCritCounts) {
  const Model m = box(4);
  const double radius = 0.004, depth = 0.001, h = 1e-7;
  const BackendTool tool = capsule(radius);
  double worst = 0;
  int checked = 0;
  for (int32_t p = 0; p < m.npoint(); ++p) {
    const Vec3 x = m.rest_position[p];
    if (std::abs(x.z() - kSize) > 1e-12 || x.x() < 1e-9 || x.y() < 1e-9 || x.x() > kSize - 1e-9 ||
        x.y() > kSize - 1e-9)
      continue;
    for (const double tilt : {0.6, 0.02})
      for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(0.003, 0, 0), Vec3(-0.0015, 0.001, 0)}) {
        const Quat turn = pose(tilt, 0.3);
        // The tip over the point for the steep shaft; the shaft's middle over it for the flat one.
        Vec3 origin = x + offset + Vec3(0, 0, radius - depth);
        if (tilt < 0.1) origin -= 0.5 * (turn * tool.end_b);
        std::vector<Vec3> xs = m.rest_position;
        const Contact f0 = at_rest(m, tool, origin, turn, &xs);
        xs[p].z() -= h;
        const Contact f1 = at_rest(m, tool, origin, turn, &xs);
        const double k_point = (f1.force[p].z() - f0.force[p].z()) / h;
        worst = std::max(worst, std::abs(k_point) / (kK * m.tool_scale(p)));
        ++checked;
      }
  }
  ASSERT_GT(checked, 40);
  // As for the sphere: k_t w_i^2 per triangle along the normal, plus the
  // turn of the direction, up to (R - d) / d of it.
  EXPECT_LT(worst, 1.0 + depth / (radius - depth));
  EXPECT_GT(worst, 0.5);
}

// A sphere has no orientation: a run with the tool turning is bitwise the
// run without, so a scenario whose keyframes carry no orientation (or any)
// steps and logs exactly as a sphere did before orientations existed.
TEST(CapsuleContact, TheSphereIgnoresTheToolsOrientationBitForBit) {
  const Model m = box(4);
  for (const ToolContact contact : {ToolContact::Surface, ToolContact::Points}) {
    const BackendTool tool{true, ToolMode::Push, 0.008, kK, contact};
    std::vector<Vec3> x[2];
    Reaction last[2];
    for (int k = 0; k < 2; ++k) {
      auto backend = make_cpu_backend(m, tool, testing::one_thread());
      TickRequest r;
      r.dt = 1e-4;
      r.substeps = 10;
      r.tool_active = true;
      for (int n = 0; n < 30; ++n) {
        r.tool_from = Vec3(0.5 * kSize, 0.5 * kSize, kSize + 0.007 - 1e-4 * n);
        r.tool_to = Vec3(0.5 * kSize, 0.5 * kSize, kSize + 0.007 - 1e-4 * (n + 1));
        if (k == 1) r.turn_from = pose(0.1 * n, n), r.turn_to = pose(0.1 * (n + 1), n + 1);
        last[k] = backend->tick(r);
      }
      backend->positions(x[k]);
    }
    ASSERT_GT(last[0].contacts, 0);
    EXPECT_EQ(last[0].force, last[1].force);
    EXPECT_EQ(last[0].torque, last[1].torque);
    EXPECT_EQ(x[0], x[1]);
  }
}

}  // namespace
}  // namespace capsule_contact_test
}  // namespace organsim
