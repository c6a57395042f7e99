// The tool's surface contact (force_law::sphere_triangle_penalty): its
// continuity across triangle edges and vertices, its stiffness bound per
// point (what dt_crit counts), its reaction against what the tissue
// receives, and the force log of a sphere sliding at constant depth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/physics/force_law.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_backend.h"
#include "core/sim/reference_forces.h"
#include "tests/core/contact_test_util.h"

namespace organsim {
namespace surface_contact_test {
namespace {

using testing::Contact;
using testing::largest_change;

constexpr double kSize = testing::kContactBox;
constexpr double kK = testing::kContactK;

Model box(int cells) { return testing::contact_box(cells); }

Contact at_rest(const Model& m, const Vec3& center, double radius) {
  Contact c;
  c.force.assign(m.npoint(), Vec3::Zero());
  c.reaction = reference_surface_forces(m, m.rest_position, center, radius, kK, c.force);
  return c;
}

// A finite-difference check: the sphere's centre moved by +-h across a
// top-face edge (through its midpoint, perpendicular to it) and around a
// top-face vertex changes the total force, the torque and every point's
// force by O(k h). A contact that dropped or doubled a triangle at the edge
// (counting each feature once, or the closest point's triangle only) would
// jump by about k * depth, a thousand times more here.
TEST(SurfaceContact, ForceAndTorqueAreContinuousAcrossEdgesAndVertices) {
  const Model m = box(4);
  const double radius = 0.006, depth = 0.002, h = 1e-7;
  const double bound = 20 * kK * h;  // a few k per m of motion, with the spread to corners
  int edges = 0, vertices = 0;
  for (int32_t t = 0; t < m.nsurface(); ++t) {
    const Tri& tri = m.surface[t];
    const Vec3 a = m.rest_position[tri[0]], b = m.rest_position[tri[1]], c = m.rest_position[tri[2]];
    if (std::abs(a.z() - kSize) + std::abs(b.z() - kSize) + std::abs(c.z() - kSize) > 1e-12) continue;
    // Edge a-b: its midpoint, and across it in the top plane.
    const Vec3 mid = 0.5 * (a + b), across = Vec3(0, 0, 1).cross(b - a).normalized();
    if (mid.x() < 0.3 * kSize || mid.x() > 0.7 * kSize || mid.y() < 0.3 * kSize || mid.y() > 0.7 * kSize) continue;
    const Vec3 center = mid + Vec3(0, 0, radius - depth);
    const Contact minus = at_rest(m, center - h * across, radius), plus = at_rest(m, center + h * across, radius);
    // k_t = k min_i s_i / n_i: about k / 6 per triangle here.
    ASSERT_GT(minus.reaction.force.norm(), 0.1 * kK * depth) << "the sphere must press on the edge";
    EXPECT_LT((plus.reaction.force - minus.reaction.force).norm(), bound) << "edge of triangle " << t;
    EXPECT_LT((plus.reaction.torque - minus.reaction.torque).norm(), bound * radius) << "edge of triangle " << t;
    EXPECT_LT(largest_change(plus, minus), bound) << "edge of triangle " << t;
    ++edges;
    // Vertex a: moved across it along x and along y.
    const Vec3 above = a + Vec3(0, 0, radius - depth);
    for (const Vec3& dir : {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0).normalized()}) {
      const Contact lo = at_rest(m, above - h * dir, radius), hi = at_rest(m, above + h * dir, radius);
      EXPECT_LT((hi.reaction.force - lo.reaction.force).norm(), bound) << "vertex " << tri[0];
      EXPECT_LT(largest_change(hi, lo), bound) << "vertex " << tri[0];
    }
    ++vertices;
  }
  EXPECT_GT(edges, 4);
  EXPECT_GT(vertices, 4);
}

// The reaction is minus the sum of the forces the reference applies, and its
// torque is that of the closest points: exact to round-off.
TEST(SurfaceContact, ReactionIsMinusTheAppliedSum) {
  const Model m = box(4);
  const Vec3 center(0.52 * kSize, 0.47 * kSize, kSize + 0.008);
  const Contact c = at_rest(m, center, 0.01);
  Vec3 sum = Vec3::Zero(), torque = Vec3::Zero();
  for (int32_t i = 0; i < m.npoint(); ++i) {
    sum += c.force[i];
    torque += (m.rest_position[i] - center).cross(c.force[i]);
  }
  ASSERT_GT(sum.norm(), 0.1 * kK * 0.002);
  EXPECT_LT((c.reaction.force + sum).norm(), 1e-12 * sum.norm());
  EXPECT_LT((c.reaction.torque + torque).norm(), 1e-12 * sum.norm() * 0.01);
}

// The tissue receives what the backend reports, with the opposite sign: one
// substep of the reference backend and of the double kernel from rest with the sphere pressed in,
// each point's contact force recovered from its motion (m (x' - x) / dt^2
// minus the internal force, which is zero at rest without gravity) must
// match the reference's, and the reaction must be minus their sum.
TEST(SurfaceContact, BackendAppliesTheReferenceForcesAndReportsMinusTheirSum) {
  const Model m = box(4);
  const BackendTool tool{true, ToolMode::Push, 0.01, kK, ToolContact::Surface};
  const Vec3 center(0.52 * kSize, 0.47 * kSize, kSize + 0.008);
  const double dt = 1e-4;
  std::vector<std::unique_ptr<Backend>> backends;
  backends.push_back(make_reference_backend(m, tool, Integrator::Verlet));
  backends.push_back(make_cpu_backend(m, tool, {Precision::Double, 1}));
  for (auto& backend : backends) {
    const Reaction got = backend->tick(testing::one_step_at(dt, center));
    const Contact want = at_rest(m, center, tool.radius);
    const testing::Applied applied = testing::applied_in_one_step(m, *backend, dt, want.force);
    const Vec3& received = applied.received;
    ASSERT_GT(applied.peak, 0.1);
    EXPECT_LT(applied.worst, 1e-8 * applied.peak) << backend->device();
    EXPECT_LT((got.force + received).norm(), 1e-8 * received.norm()) << backend->device();
    EXPECT_LT((got.force - want.reaction.force).norm(), 1e-12 * received.norm()) << backend->device();
    EXPECT_EQ(got.contacts, want.reaction.contacts);
  }
}

// Every point's contact stiffness (the derivative of its own force along
// the normal) stays within k s_i, the bound dt_crit counts, wherever the
// sphere presses: on vertices (where all a point's triangles push it with
// full weight), edges and faces.
TEST(SurfaceContact, StiffnessPerPointStaysWithinTheBoundDtCritCounts) {
  const Model m = box(4);
  const double radius = 0.005, depth = 0.001, h = 1e-7;
  double worst = 0;
  int checked = 0;
  for (int32_t p = 0; p < m.npoint(); ++p) {
    const Vec3 x = m.rest_position[p];
    if (std::abs(x.z() - kSize) > 1e-12 || x.x() < 1e-9 || x.y() < 1e-9 || x.x() > kSize - 1e-9 ||
        x.y() > kSize - 1e-9)
      continue;
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(0.003, 0, 0), Vec3(0.002, 0.002, 0), Vec3(-0.0015, 0.001, 0)}) {
      const Vec3 center = x + offset + Vec3(0, 0, radius - depth);
      std::vector<Vec3> xs = m.rest_position;
      std::vector<Vec3> f0(m.npoint(), Vec3::Zero()), f1(m.npoint(), Vec3::Zero());
      reference_surface_forces(m, xs, center, radius, kK, f0);
      xs[p].z() -= h;  // moved down by h, away from the centre: the push along -z weakens
      reference_surface_forces(m, xs, center, radius, kK, f1);
      const double k_point = (f1[p].z() - f0[p].z()) / h;
      worst = std::max(worst, std::abs(k_point) / (kK * m.tool_scale(p)));
      ++checked;
    }
  }
  ASSERT_GT(checked, 20);
  // Along the normal the penalty is k_t w_i^2 per triangle; the direction
  // (q - c) / |q - c| also turns as the point moves, which adds up to
  // (R - d) / d of it, as for the point penalty (depth / (radius - depth)).
  EXPECT_LT(worst, 1.0 + depth / (radius - depth));
  EXPECT_GT(worst, 0.5);  // nearly reached where a vertex is pressed: the bound is not loose
}

// A sphere sliding along the top at constant depth: the force log is
// smooth (tick-to-tick change of |F| below 5 % of its mean) with surface
// contact; with the penalty on the points it jumps as points enter and
// leave the sphere, which is what the test must be able to see.
double largest_tick_change_sliding(ToolContact contact, double& mean, bool hertz_layer = false) {
  const Model m = box(4);  // 1 cm cells under a 6 mm sphere
  BackendTool tool{true, ToolMode::Push, 0.006, kK, contact};
  tool.hertz_layer = hertz_layer;
  auto backend = make_cpu_backend(m, tool, testing::one_thread());
  TickRequest r;
  r.dt = 1e-4;
  r.substeps = 10;
  r.tool_active = true;
  const double z = kSize + tool.radius - 0.0015;
  const Vec3 a(0.2 * kSize, 0.43 * kSize, z), b(0.8 * kSize, 0.57 * kSize, z);
  const int settle = 100, slide = 400;
  std::vector<double> force;
  for (int n = 0; n < settle + slide; ++n) {
    const double s0 = std::max(0, n - settle) / double(slide), s1 = std::max(0, n + 1 - settle) / double(slide);
    r.tool_from = a + s0 * (b - a);
    r.tool_to = a + s1 * (b - a);
    const Reaction reaction = backend->tick(r);
    if (n >= settle) force.push_back(reaction.force.norm());
  }
  mean = 0;
  for (double f : force) mean += f / force.size();
  double worst = 0;
  for (size_t i = 1; i < force.size(); ++i) worst = std::max(worst, std::abs(force[i] - force[i - 1]));
  return worst;
}

TEST(SurfaceContact, SlidingAtConstantDepthGivesASmoothForce) {
  double mean = 0;
  const double surface = largest_tick_change_sliding(ToolContact::Surface, mean);
  ASSERT_GT(mean, 0.02 * kK * 0.0015);  // k_t is about k / 6 per triangle
  EXPECT_LT(surface, 0.05 * mean);
  double mean_points = 0;
  const double points = largest_tick_change_sliding(ToolContact::Points, mean_points);
  EXPECT_GT(points, 0.05 * mean_points) << "point contact should jump here; the test would see nothing";
  std::cout << "sliding: largest tick-to-tick change " << surface / mean << " of the mean with surface contact, "
            << points / mean_points << " with point contact\n";
}

// The same with the sub-cell Hertz layer: triangles entering the contact at
// zero depth must not change the layer's force by more than their own
// penalty (a layer whose stiffness took each newcomer's k_t whole, though
// its penalty cannot fall below zero, dropped the force by 15 % in a tick).
TEST(SurfaceContact, SlidingAtConstantDepthGivesASmoothForceWithTheHertzLayer) {
  double mean = 0;
  const double layered = largest_tick_change_sliding(ToolContact::Surface, mean, true);
  ASSERT_GT(mean, 0.005 * kK * 0.0015);
  EXPECT_LT(layered, 0.05 * mean);
  std::cout << "sliding with the Hertz layer: largest tick-to-tick change " << layered / mean << " of the mean\n";
}

// The surface contact's positions and box tests are split over the step's
// threads, its penalties summed on one: a sphere pressed in and sliding gives
// the same reactions and positions, bit for bit, on 1, 2 and 3 threads (3
// splits the triangles unevenly), in both precisions.
TEST(SurfaceContact, ThreadsGiveOneThreadsResultBitForBit) {
  const Model m = box(6);
  const BackendTool tool{true, ToolMode::Push, 0.008, kK, ToolContact::Surface};
  for (const Precision precision : {Precision::Float, Precision::Double}) {
    std::vector<Vec3> first_force, first_positions;
    for (const int32_t threads : {1, 2, 3}) {
      SCOPED_TRACE(std::to_string(threads) + " threads, " + (precision == Precision::Float ? "float" : "double"));
      auto backend = make_cpu_backend(m, tool, {precision, threads});
      TickRequest r;
      r.dt = 1e-4;
      r.substeps = 4;
      r.tool_active = true;
      const Vec3 a(0.3 * kSize, 0.4 * kSize, kSize + tool.radius + 0.001), b(0.7 * kSize, 0.6 * kSize, kSize + 0.006);
      std::vector<Vec3> force;
      int32_t touching = 0;
      for (int n = 0; n < 150; ++n) {
        r.tool_from = a + (n / 150.0) * (b - a);
        r.tool_to = a + ((n + 1) / 150.0) * (b - a);
        const Reaction reaction = backend->tick(r);
        force.push_back(reaction.force);
        touching = std::max(touching, reaction.contacts);
      }
      std::vector<Vec3> positions;
      backend->positions(positions);
      EXPECT_GT(touching, 6);  // several triangles' corners: the split matters
      if (threads == 1) {
        first_force = force, first_positions = positions;
        continue;
      }
      EXPECT_TRUE(force == first_force);
      EXPECT_TRUE(positions == first_positions);
    }
  }
}

// The surface the contact uses is the Model's boundary, re-extracted by a
// rebuild: a cut opens new faces, and each point's triangles follow.
TEST(SurfaceContact, RebuildReExtractsTheSurface) {
  const Model m = box(4);
  const Model cut = rebuild_model(m, testing::split_across_plane_x(m, 0.5 * kSize));
  EXPECT_GT(cut.nsurface(), m.nsurface());
  int32_t listed = 0;
  for (int32_t p = 0; p < cut.npoint(); ++p) {
    for (int32_t e = cut.surface_offset[p]; e < cut.surface_offset[p + 1]; ++e) {
      const Tri& t = cut.surface[cut.surface_tri[e]];
      EXPECT_TRUE(t[0] == p || t[1] == p || t[2] == p);
      ++listed;
    }
  }
  EXPECT_EQ(listed, 3 * cut.nsurface());
}

}  // namespace
}  // namespace surface_contact_test
}  // namespace organsim
