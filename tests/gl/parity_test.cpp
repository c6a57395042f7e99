// The GL backend against the double-precision CPU reference over 1000 steps
// (100 ticks x 10 substeps of 0.1 ms) of a push, a pull and a lean scene, on
// box models built in the test (the liver_push/liver_pull scenario files mesh
// a surface with CGAL; these tests stay CGAL-free and fast).
//
// Tolerances (single precision; docs/gl.md "Accuracy"):
// - positions, 1e-5 of the bounding-box diagonal: float stores 0.1 m
//   coordinates to ~4e-9 m (4e-8 of the 0.12 m diagonal) and each step rounds
//   x_{t+1} = x_t + d once more; as the GL state keeps d = x_t - x_{t-1}
//   itself, those roundings do not feed the velocity, so they random-walk:
//   ~sqrt(1000) x 4e-8 ~ 1e-6. Measured: 5e-7 (push, pull), 1.2e-6 (lean
//   cantilever, larger motion). A wrong force term moves points by
//   millimetres (1e-2 of the diagonal); storing x_{t-1} instead of d gives
//   ~1e-3 (the CPU float path does, measured 0.6-1.5e-3 on these scenes).
// - tool force, 1e-4 of the peak reaction: each contact's force is
//   k_c x penetration, so a position error e changes it by k_c e: with
//   e ~ 1e-7 m, k_c = 200 N/m against a ~1.4 N peak that is ~1e-5 per
//   contact. Measured: 5-6e-6.
#include <gtest/gtest.h>

#include <functional>
#include <set>

#include "core/gl/gl_backend.h"
#include "core/gl/gl_model_pack.h"
#include "shaders/bindings.glsl.h"
#include "core/sim/reference_backend.h"
#include "gl_test_scenes.h"

namespace organsim {
namespace parity_test {
namespace {

constexpr double kDt = 1e-4;    // s
constexpr int kSubsteps = 10;   // per tick
constexpr int kTicks = 100;     // 1000 steps

struct Comparison {
  double position = 0;    // max over ticks and points |x_gl - x_cpu| / bbox diagonal
  double force = 0;       // max over ticks |F_gl - F_cpu| / max |F_cpu|
  double peak_force = 0;  // N
  double grip = 0;        // max over ticks |grip_gl - grip_cpu| / max grip_cpu
  int32_t max_contacts = 0;
  int64_t dispatches = 0, blocked = 0;
};

// Runs both backends through the same ticks. The GL reaction of tick n is
// returned by tick n+1 (latency 1), so it is compared with the CPU's tick n.
// GL runs with `threads_per_point` invocations per point (0: the backend's default).
Comparison compare(const Model& model, const BackendTool& tool, const std::function<TickRequest(int)>& request_at,
                   const Attachment* attachment = nullptr, int32_t threads_per_point = 0) {
  // One thread: the machine is shared and OpenMP spinning under load is slow.
  auto cpu = make_reference_backend(model, tool, Integrator::Verlet);

  GlBackendOptions options;
  options.threads_per_point = threads_per_point;
  GlBackend gl(model, tool, options);
  EXPECT_EQ(cpu->reaction_latency_ticks(), 0);
  EXPECT_EQ(gl.reaction_latency_ticks(), 1);
  if (attachment) {
    cpu->attach(*attachment);
    gl.attach(*attachment);
  }
  const double diagonal = gl_test::bbox_diagonal(model);
  Comparison c;
  std::vector<Reaction> cpu_reaction, gl_reaction;
  std::vector<Vec3> xc, xg;
  for (int n = 0; n <= kTicks; ++n) {
    TickRequest r = request_at(std::min(n, kTicks - 1));
    if (n == kTicks) r.substeps = 1;  // one more (GL only) to fetch the last reaction
    if (n < kTicks) cpu_reaction.push_back(cpu->tick(r));
    const Reaction g = gl.tick(r);
    if (n > 0) gl_reaction.push_back(g);
    if (n < kTicks && (n % 10 == 9)) {
      cpu->positions(xc);
      gl.positions(xg);
      for (size_t i = 0; i < xc.size(); ++i) c.position = std::max(c.position, (xc[i] - xg[i]).norm() / diagonal);
    }
  }
  double worst = 0, worst_grip = 0, peak_grip = 0;
  for (int n = 0; n < kTicks; ++n) {
    c.peak_force = std::max(c.peak_force, cpu_reaction[n].force.norm());
    worst = std::max(worst, (cpu_reaction[n].force - gl_reaction[n].force).norm());
    peak_grip = std::max(peak_grip, cpu_reaction[n].grip);
    worst_grip = std::max(worst_grip, std::abs(cpu_reaction[n].grip - gl_reaction[n].grip));
    c.max_contacts = std::max(c.max_contacts, cpu_reaction[n].contacts);
  }
  c.force = c.peak_force > 0 ? worst / c.peak_force : worst;
  c.grip = peak_grip > 0 ? worst_grip / peak_grip : worst_grip;
  c.dispatches = gl.dispatches();
  c.blocked = gl.blocked_readbacks();
  return c;
}

TickRequest tool_request(int n, const Vec3& start, const Vec3& end) {
  TickRequest r;
  r.dt = kDt;
  r.substeps = kSubsteps;
  r.tool_active = true;
  r.tool_from = start + (end - start) * (static_cast<double>(n) / kTicks);
  r.tool_to = start + (end - start) * (static_cast<double>(n + 1) / kTicks);
  return r;
}

// With one invocation per point (llvmpipe's default) and with 8 (a GPU's):
// the trajectory, not only one substep's force (kernel_test.cpp), with each
// point's gathers split over the invocations.
TEST(GlParity, PushMatchesTheDoubleReference) {
  // Volume, gravity, fixed bottom; a 2 cm sphere pressed 1.5 cm into the top,
  // against the surface triangles (the default contact): each GL point
  // recomputes its own triangles, the CPU evaluates each triangle once.
  const Model model = gl_test::box_model(8, 8, 4, true, 2e4, Vec3(0, 0, -9.81));
  const BackendTool tool{true, ToolMode::Push, 0.02, 200.0};
  const Vec3 start(0.05, 0.05, 0.072), end(0.05, 0.05, 0.055);
  for (const int32_t threads_per_point : {1, 8}) {
    SCOPED_TRACE(std::to_string(threads_per_point) + " invocation(s) per point");
    const Comparison c =
        compare(model, tool, [&](int n) { return tool_request(n, start, end); }, nullptr, threads_per_point);
    std::cout << "push, " << threads_per_point << " invocation(s) per point: position " << c.position
              << " of diagonal, force " << c.force << " of peak " << c.peak_force << " N, " << c.max_contacts
              << " contacts, " << c.dispatches << " dispatches, " << c.blocked << " blocked readbacks\n";
    ASSERT_GT(c.max_contacts, 3);
    ASSERT_GT(c.peak_force, 0.1);
    EXPECT_LT(c.position, 1e-5);
    EXPECT_LT(c.force, 1e-4);
    // One fused dispatch per substep plus one reduction per tick (the extra
    // one-substep tick that fetches the last reaction adds 2).
    EXPECT_EQ(c.dispatches, kTicks * (kSubsteps + 1) + 2);
  }
}

// The same press with the penalty on the points (tool.contact "points").
TEST(GlParity, PushOnThePointsMatchesTheDoubleReference) {
  const Model model = gl_test::box_model(8, 8, 4, true, 2e4, Vec3(0, 0, -9.81));
  const BackendTool tool{true, ToolMode::Push, 0.02, 200.0, ToolContact::Points};
  const Vec3 start(0.05, 0.05, 0.072), end(0.05, 0.05, 0.055);
  for (const int32_t threads_per_point : {1, 8}) {
    SCOPED_TRACE(std::to_string(threads_per_point) + " invocation(s) per point");
    const Comparison c =
        compare(model, tool, [&](int n) { return tool_request(n, start, end); }, nullptr, threads_per_point);
    ASSERT_GT(c.max_contacts, 3);
    ASSERT_GT(c.peak_force, 0.1);
    EXPECT_LT(c.position, 1e-5);
    EXPECT_LT(c.force, 1e-4);
  }
}

// A capsule (a 4 cm shaft, radius 12 mm, its tip the tool's origin) pressed
// into the top while it turns a quarter turn about z, against the surface
// triangles and on the points: the closest points between segment and
// triangle, and the pose's slerp per substep, on both backends.
TEST(GlParity, TurningCapsuleMatchesTheDoubleReference) {
  const Model model = gl_test::box_model(8, 8, 4, true, 2e4, Vec3(0, 0, -9.81));
  const Vec3 start(0.05, 0.05, 0.068), end(0.05, 0.05, 0.056);
  // Tilted so that the shaft rises from the tip; the tip ends 6 mm deep.
  const Quat from(Eigen::AngleAxisd(-0.3, Vec3::UnitY())), to = Quat(Eigen::AngleAxisd(1.5708, Vec3::UnitZ())) * from;
  auto request_at = [&](int n) {
    TickRequest r = tool_request(n, start, end);
    r.turn_from = from.slerp(static_cast<double>(n) / kTicks, to);
    r.turn_to = from.slerp(static_cast<double>(n + 1) / kTicks, to);
    return r;
  };
  for (const ToolContact contact : {ToolContact::Surface, ToolContact::Points})
    for (const int32_t threads_per_point : {1, 8}) {
      SCOPED_TRACE(std::string(contact == ToolContact::Surface ? "surface" : "points") + ", " +
                   std::to_string(threads_per_point) + " invocation(s) per point");
      BackendTool tool{true, ToolMode::Push, 0.012, 200.0, contact};
      tool.shape = ToolShape::Capsule;
      tool.end_b = Vec3(0.04, 0, 0);
      const Comparison c = compare(model, tool, request_at, nullptr, threads_per_point);
      std::cout << "capsule, " << (contact == ToolContact::Surface ? "surface" : "points") << ", "
                << threads_per_point << " invocation(s) per point: position " << c.position << " of diagonal, force "
                << c.force << " of peak " << c.peak_force << " N, " << c.max_contacts << " contacts\n";
      // On the points the tissue gives way under the tip: one point carries it
      // (the surface contact spreads it over several triangles' corners).
      ASSERT_GT(c.max_contacts, contact == ToolContact::Surface ? 3 : 0);
      ASSERT_GT(c.peak_force, 0.1);
      EXPECT_LT(c.position, 1e-5);
      EXPECT_LT(c.force, 1e-4);
    }
}

// A grasper (two capsule jaws of radius 6 mm along x, one on each side of
// the box in y, 1.5 cm below its top) closes 3 mm into both sides over 60
// ticks, then lifts 0.5 mm while turning 0.02 rad, holding by friction (the
// jaws skewed a little across the faces): the
// jaws' two segments, each point's anchor kept in the turning tool frame,
// and the grip summed with the reaction, on both backends. The friction
// coefficient is high enough that no point slips: which point slips first
// at a substep turns on the last bits, so past a slip float follows double
// in what the grasp does, not tick by tick
// (Grasper.PrecisionsAndThreadsFollowTheDoubleReference measures it
// on the CPU). Looser than the sphere's: the jaws lie nearly parallel to
// the faces, where a capsule's closest point on a triangle jumps along the
// jaw as float and double break near-ties differently (docs/physics.md, the
// capsule's limits); without friction the jaws alone differ by 5e-5 of the
// diagonal and 1e-3 of the peak force, with it by 3e-5 and 1e-2.
TEST(GlParity, GraspingJawsWithFrictionMatchTheDoubleReference) {
  const Model model = gl_test::box_model(8, 8, 4, true, 2e4, Vec3(0, 0, -9.81));
  BackendTool tool{true, ToolMode::Push, 0.006, 200.0, ToolContact::Surface};
  tool.shape = ToolShape::Grasper;
  tool.end_a = Vec3(-0.07, 0, 0);
  tool.end_b = Vec3(0.07, 0, 0);
  tool.friction = {50, 50};
  const Vec3 at(0.05, 0.05, 0.035);
  const double open = 0.1 + 2 * 0.006 + 0.002, closed = 0.1 + 2 * 0.006 - 2 * 0.003;
  // Skewed 0.03 rad about z: jaws parallel to the faces would meet every
  // triangle at a tie of closest points, which float and double break
  // differently (docs/physics.md, the capsule's limits).
  const Quat from(Eigen::AngleAxisd(0.03, Vec3::UnitZ())), to = Quat(Eigen::AngleAxisd(0.02, Vec3::UnitY())) * from;
  auto request_at = [&](int n) {
    auto lift = [&](int k) -> Vec3 { return at + Vec3(0, 0, 0.0005 * std::max(0, k - 60) / 40.0); };
    auto gap = [&](int k) { return open + (closed - open) * std::min(k, 60) / 60.0; };
    auto turn = [&](int k) { return from.slerp(std::max(0, k - 60) / 40.0, to); };
    TickRequest r = tool_request(n, at, at);
    r.tool_from = lift(n), r.tool_to = lift(n + 1);
    r.gap_from = gap(n), r.gap_to = gap(n + 1);
    r.turn_from = turn(n), r.turn_to = turn(n + 1);
    return r;
  };
  for (const int32_t threads_per_point : {1, 8}) {
    SCOPED_TRACE(std::to_string(threads_per_point) + " invocation(s) per point");
    const Comparison c = compare(model, tool, request_at, nullptr, threads_per_point);
    std::cout << "grasper, " << threads_per_point << " invocation(s) per point: position " << c.position
              << " of diagonal, force " << c.force << " of peak " << c.peak_force << " N, grip " << c.grip << ", "
              << c.max_contacts << " contacts\n";
    ASSERT_GT(c.max_contacts, 10);
    ASSERT_GT(c.peak_force, 0.05);
    EXPECT_LT(c.position, 1e-4);
    EXPECT_LT(c.force, 2e-2);
    EXPECT_LT(c.grip, 2e-4);
  }
}

// Above 4,096 points there are more than 64 chunks, so the reduction's 64
// lanes each sum several workgroup partials before the tree: the contacts
// must be counted whichever chunk they fall in. Same tolerances as above.
TEST(GlParity, ReactionOverMoreThan64ChunksMatchesTheDoubleReference) {
  const Model model = gl_test::box_model(20, 20, 10, true, 2e4, Vec3(0, 0, -9.81));  // 21 x 21 x 11 points
  ASSERT_GT(model.npoint(), 64 * 64);
  // A 3 cm sphere pressed 8 mm into the top face (z = 0.05) above the top
  // points in chunks 64 and up (the locality order puts them in one corner),
  // so the points under it lie in chunks on both sides of chunk 64 and both
  // parts of the lanes' loop carry contact forces.
  Vec3 corner(0, 0, 0);
  int ncorner = 0;
  for (int32_t i = 64 * 64; i < model.npoint(); ++i) {
    if (model.rest_position[i].z() > 0.05 - 1e-9) corner += model.rest_position[i], ++ncorner;
  }
  ASSERT_GT(ncorner, 0);
  corner /= ncorner;
  const BackendTool tool{true, ToolMode::Push, 0.03, 200.0};
  const Vec3 start(corner.x(), corner.y(), 0.082), end(corner.x(), corner.y(), 0.072);
  int32_t below = 0, above = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if ((model.rest_position[i] - end).norm() < tool.radius) (i < 64 * 64 ? below : above) += 1;
  }
  ASSERT_GT(below, 0);
  ASSERT_GT(above, 0);
  const Comparison c = compare(model, tool, [&](int n) { return tool_request(n, start, end); });
  std::cout << "push over " << model.npoint() << " points: force " << c.force << " of peak " << c.peak_force
            << " N, " << c.max_contacts << " contacts\n";
  ASSERT_GT(c.max_contacts, 10);
  EXPECT_LT(c.position, 1e-5);
  EXPECT_LT(c.force, 1e-4);
}

TEST(GlParity, PullMatchesTheDoubleReference) {
  const Model model = gl_test::box_model(8, 8, 4, true, 2e4, Vec3(0, 0, -9.81));
  const BackendTool tool{true, ToolMode::Pull, 0.01, 200.0};
  const Vec3 grasp(0.05, 0.05, 0.05), end = grasp + Vec3(0.004, 0, 0.012);
  Attachment attachment;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if ((model.rest_position[i] - grasp).norm() < 0.015) {
      attachment.points.push_back(i);
      attachment.offsets.push_back(model.rest_position[i] - grasp);
    }
  }
  ASSERT_GE(attachment.points.size(), 4u);
  const Comparison c = compare(model, tool, [&](int n) { return tool_request(n, grasp, end); }, &attachment);
  std::cout << "pull: position " << c.position << " of diagonal, force " << c.force << " of peak " << c.peak_force
            << " N, " << c.max_contacts << " attached\n";
  ASSERT_GT(c.peak_force, 0.1);
  EXPECT_LT(c.position, 1e-5);
  EXPECT_LT(c.force, 1e-4);
}

TEST(GlParity, LeanSceneMatchesTheDoubleReference) {
  // Springs and gravity only: a cantilever fixed at x = 0 sagging, no volume
  // pass and no tool kernels compiled in.
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.02, 0.02), 10, 2, 2);
  Material material;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  FixedSelector wall;
  wall.kind = FixedSelector::Kind::Plane;
  wall.point = Vec3(1e-9, 0, 0);
  wall.normal = Vec3(-1, 0, 0);
  options.fixed.push_back(wall);
  const Model model = build_model(mesh, material, options, "cantilever");
  ASSERT_FALSE(model.has_volume());
  const Comparison c = compare(model, BackendTool{}, [](int) {
    TickRequest r;
    r.dt = kDt;
    r.substeps = kSubsteps;
    return r;
  });
  std::vector<Vec3> x;
  std::cout << "lean: position " << c.position << " of diagonal, " << c.dispatches << " dispatches\n";
  EXPECT_LT(c.position, 1e-5);
  EXPECT_EQ(c.dispatches, (kTicks + 1) * kSubsteps - (kSubsteps - 1));  // no reduction without a tool
}

// A 1 cm sphere pressed 3 mm into 1.25 cm cells with the sub-cell Hertz
// layer: hertz_layer_touch.comp's penalties, hertz_layer.comp's solve over
// the blocks in contact (one workgroup per substep, float) and step.comp's
// factors follow the double reference's HertzLayer over the
// trajectory, with 1 and 8 invocations per point; the layer acted (the peak
// is well below the same press without it).
TEST(GlParity, PushWithTheHertzLayerMatchesTheDoubleReference) {
  const Model model = gl_test::box_model(8, 8, 4, true, 2e4, Vec3(0, 0, -9.81));
  BackendTool tool{true, ToolMode::Push, 0.01, 200.0};
  const Vec3 start(0.052, 0.048, 0.061), end(0.052, 0.048, 0.057);
  const auto request = [&](int n) { return tool_request(n, start, end); };
  const double plain_peak = compare(model, tool, request).peak_force;
  tool.hertz_layer = true;
  for (const int32_t threads_per_point : {1, 8}) {
    SCOPED_TRACE(std::to_string(threads_per_point) + " invocation(s) per point");
    const Comparison c = compare(model, tool, request, nullptr, threads_per_point);
    std::cout << "push with the Hertz layer, " << threads_per_point << " invocation(s) per point: position "
              << c.position << " of diagonal, force " << c.force << " of peak " << c.peak_force << " N (without the layer "
              << plain_peak << " N), " << c.max_contacts << " contacts\n";
    ASSERT_GT(c.max_contacts, 2);
    ASSERT_GT(c.peak_force, 0.01);
    EXPECT_LT(c.peak_force, 0.9 * plain_peak);
    EXPECT_LT(c.position, 1e-5);
    EXPECT_LT(c.force, 1e-4);
    // A step per substep (GL's extra tick has one) and a reduce per tick,
    // plus the layer's two passes before every step, while the tool acts.
    const int64_t steps = kTicks * kSubsteps + 1;
    EXPECT_EQ(c.dispatches, steps + (kTicks + 1) + 2 * steps);
  }
}

// A capsule (a 4 cm shaft, radius 12 mm, its tip the tool's origin) pressed
// in on its tip while it turns from 17 degrees to lying flat: its layer goes
// from Hertz's law at the tip through the blend to the line's along the
// shaft (hertz_layer.comp's spread along the axis and its regula falsi),
// following the double reference with 1 and 8 invocations per point; the
// layer acted.
TEST(GlParity, CapsuleLyingDownWithItsLayerMatchesTheDoubleReference) {
  const Model model = gl_test::box_model(8, 8, 4, true, 2e4, Vec3(0, 0, -9.81));
  BackendTool tool{true, ToolMode::Push, 0.012, 200.0};
  tool.shape = ToolShape::Capsule;
  tool.end_b = Vec3(0.04, 0, 0);
  const Vec3 start(0.03, 0.05, 0.064), end(0.03, 0.05, 0.058);
  const Quat from(Eigen::AngleAxisd(-0.3, Vec3::UnitY())), to = Quat::Identity();
  auto request = [&](int n) {
    TickRequest r = tool_request(n, start, end);
    r.turn_from = from.slerp(static_cast<double>(n) / kTicks, to);
    r.turn_to = from.slerp(static_cast<double>(n + 1) / kTicks, to);
    return r;
  };
  const double plain_peak = compare(model, tool, request).peak_force;
  tool.hertz_layer = true;
  for (const int32_t threads_per_point : {1, 8}) {
    SCOPED_TRACE(std::to_string(threads_per_point) + " invocation(s) per point");
    const Comparison c = compare(model, tool, request, nullptr, threads_per_point);
    std::cout << "capsule lying down with its layer, " << threads_per_point << " invocation(s) per point: position "
              << c.position << " of diagonal, force " << c.force << " of peak " << c.peak_force
              << " N (without the layer " << plain_peak << " N), " << c.max_contacts << " contacts\n";
    ASSERT_GT(c.max_contacts, 10);
    ASSERT_GT(c.peak_force, 0.01);
    EXPECT_LT(c.peak_force, 0.9 * plain_peak);
    EXPECT_LT(c.position, 1e-5);
    EXPECT_LT(c.force, 1e-4);
  }
}

// A 2 cm sphere pressed 3 mm into the middle of a finer box's top face: its
// contact falls in several of the layer's blocks of ORGANSIM_GL_LAYER_SIZE
// triangles (checked on the packed table), and the solve over all of them
// follows the double reference with the same tolerances.
TEST(GlParity, TheHertzLayerSolvesAContactAcrossSeveralBlocks) {
  const Model model = gl_test::box_model(16, 16, 2, true, 2e4, Vec3(0, 0, -9.81));
  BackendTool tool{true, ToolMode::Push, 0.02, 200.0};
  tool.hertz_layer = true;
  const Vec3 start(0.051, 0.049, 0.071), end(0.051, 0.049, 0.067);
  const gl::PackedModel packed = gl::pack_model(model, true);
  std::set<size_t> blocks;
  for (size_t i = 0; i < packed.layer_tris.size(); ++i) {
    const int32_t* corner = packed.layer_tris[i].corners;
    for (int k = 0; k < 3; ++k)
      if ((model.rest_position[corner[k]] - end).norm() < tool.radius) blocks.insert(i / ORGANSIM_GL_LAYER_SIZE);
  }
  ASSERT_GE(blocks.size(), 2u);
  const Comparison c = compare(model, tool, [&](int n) { return tool_request(n, start, end); });
  std::cout << "Hertz layer across " << blocks.size() << " blocks: position " << c.position << " of diagonal, force "
            << c.force << " of peak " << c.peak_force << " N, " << c.max_contacts << " contacts\n";
  ASSERT_GT(c.max_contacts, 10);
  EXPECT_LT(c.position, 1e-5);
  EXPECT_LT(c.force, 1e-4);
}

}  // namespace
}  // namespace parity_test
}  // namespace organsim
