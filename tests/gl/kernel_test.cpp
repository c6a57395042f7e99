// Each part of the fused step kernel against its CPU twin in
// core/sim/reference_forces.h: total force per point after one step, on a
// randomly deformed box (springs, dampers, volume, gravity, push, pull).
//
// Tolerance: the kernel sees exactly the reference's input (positions
// rounded to float), so only float arithmetic differs: each spring term has
// a relative error of a few 1e-7 and a point sums ~14 springs and ~24 tets
// whose terms largely cancel (measured: 5e-7), so we allow 1e-5 of the largest force in the
// model (a wrong sign, index or formula gives errors of order 1).
//
// Each test runs with 1, 3 and 8 invocations per point (step.comp's
// THREADS_PER_POINT: 1 is what llvmpipe runs, 8 what a GPU runs; 3 does not
// divide the slot counts evenly). The partial sums are added in another
// order than one invocation's, which the same tolerance covers.
#include <gtest/gtest.h>

#include "core/gl/gl_backend.h"
#include "core/gl/gl_program.h"
#include "core/sim/reference_forces.h"
#include "core/util/error.h"
#include "gl_test_scenes.h"
#include "shaders/bindings.glsl.h"
#include "tests/core/contact_test_util.h"

namespace organsim {
namespace kernel_test {
namespace {

constexpr double kDt = 1e-4;  // s

class GlKernel : public ::testing::TestWithParam<int32_t> {
 protected:
  GlBackendOptions recording() const {
    GlBackendOptions options;
    options.record_forces = true;
    options.threads_per_point = GetParam();
    return options;
  }
};

double max_norm(const std::vector<Vec3>& f) {
  double m = 0;
  for (const Vec3& v : f) m = std::max(m, v.norm());
  return m;
}

// max_i |a_i - b_i| / max_i |b_i|
double relative_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, (a[i] - b[i]).norm());
  return d / max_norm(b);
}

TEST_P(GlKernel, SpringsVolumeAndGravityMatchTheReferenceScatter) {
  const Model model = gl_test::box_model(5, 5, 3, true, 2e4, Vec3(0, 0, -9.81));
  ASSERT_TRUE(model.has_volume());
  const GlBackendOptions options = recording();
  GlBackend gl(model, BackendTool{}, options);
  const gl_test::MovingState s = gl_test::moving_state(model, kDt);
  const std::vector<Vec3> got = gl_test::forces_of_one_substep(gl, s, kDt);
  std::vector<Vec3> want;
  reference_internal_forces(model, s.x, s.v, want);
  const double rel = relative_difference(got, want);
  std::cout << "springs+volume+gravity: max |f_gl - f_ref| / max |f_ref| = " << rel << " (max |f| "
            << max_norm(want) << " N)\n";
  EXPECT_LT(rel, 1e-5);

  // And the integration of that force: x_{t+1} = x + (1 - alpha dt)(x - x_prev) + dt^2 f/m.
  std::vector<Vec3> x_next;
  gl.positions(x_next);
  double worst = 0, scale = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    const Vec3 expect = model.inv_mass[i] > 0 ? Vec3(s.x[i] + (1 - model.viscous_damping * kDt) * (s.x[i] - s.x_prev[i]) +
                                                     kDt * kDt * model.inv_mass[i] * want[i])
                                              : s.x[i];
    worst = std::max(worst, (x_next[i] - expect).norm());
    scale = std::max(scale, (expect - s.x[i]).norm());
  }
  std::cout << "integration: max |x_gl - x_ref| = " << worst << " m, step size " << scale << " m\n";
  // Positions are float: 0.1 m coordinates round to ~4e-9 m; allow 4 ulps.
  EXPECT_LT(worst, 3e-8);
  EXPECT_GT(scale, 1e-7);  // the step moved points by more than the tolerance
}

// Both contacts: the penalty on the surface triangles (each GL point
// recomputing its own triangles) and on the points.
TEST_P(GlKernel, PushContactAndReactionMatchTheReference) {
  const Model model = gl_test::box_model(5, 5, 3, true, 0, Vec3(0, 0, 0));
  for (const ToolShape shape : {ToolShape::Sphere, ToolShape::Capsule})
  for (const ToolContact contact : {ToolContact::Surface, ToolContact::Points}) {
    SCOPED_TRACE(std::string(shape_name(shape)) + (contact == ToolContact::Surface ? ", surface contact" : ", point contact"));
    BackendTool tool{true, ToolMode::Push, 0.02, 300.0, contact};
    // The capsule: a 4 cm shaft of the sphere's radius whose tip is the
    // tool's origin, turned 30 degrees about x, so its closest points lie
    // off the origin and the reaction has a torque about it.
    const Quat turn(Eigen::AngleAxisd(0.5236, Vec3::UnitX()));
    if (shape == ToolShape::Capsule) tool.shape = shape, tool.end_b = Vec3(0.04, 0, 0.01);
    const GlBackendOptions options = recording();
    GlBackend gl(model, tool, options);
    const gl_test::MovingState s = gl_test::moving_state(model, kDt);
    gl.set_state(s.x, s.x_prev);
    // Tool centre 1.2 cm above the top face's centre: the top points nearest the
    // centre are inside the 2 cm sphere (the capsule's tip).
    const Vec3 center(0.05, 0.05, 0.062);
    TickRequest request = testing::one_step_at(kDt, center, turn);
    EXPECT_EQ(gl.tick(request).contacts, 0);  // latency: nothing read yet
    std::vector<Vec3> got, want;
    gl.forces(got);
    reference_internal_forces(model, s.x, s.v, want);
    const ToolPlacement placed = request.tool_at(tool, 0);
    const Reaction expect =
        contact == ToolContact::Surface
            ? reference_surface_forces(model, s.x, placed, tool.contact_stiffness, want)
            : reference_push_forces(s.x, placed, tool.contact_stiffness, want, model.tool_k_scale);
    ASSERT_GT(expect.contacts, 0);
    EXPECT_LT(relative_difference(got, want), 1e-5);
    // The reaction of that tick comes back with the next one.
    request.tool_active = false;
    const Reaction r = gl.tick(request);
    EXPECT_EQ(r.contacts, expect.contacts);
    std::cout << shape_name(shape) << " push reaction " << r.force.transpose() << " N, reference "
              << expect.force.transpose() << " N, torque " << r.torque.transpose() << " N m, reference "
              << expect.torque.transpose() << " N m, " << r.contacts << " contacts\n";
    // The reaction sums tens of float terms of one sign: 1e-5 relative.
    EXPECT_LT((r.force - expect.force).norm(), 1e-5 * expect.force.norm());
    if (shape == ToolShape::Sphere) {
      // Torque about the centre of forces along (contact point - centre) is 0 up to rounding.
      EXPECT_LT(r.torque.norm(), 1e-6 * expect.force.norm() * tool.radius);
    } else {
      // The capsule's torque about its origin: lever arms up to the 4 cm shaft.
      ASSERT_GT(expect.torque.norm(), 1e-3 * expect.force.norm() * tool.radius);
      EXPECT_LT((r.torque - expect.torque).norm(), 1e-5 * expect.force.norm() * 0.04);
    }
  }
}

TEST_P(GlKernel, PullAttachmentsAndReactionMatchTheReference) {
  const Model model = gl_test::box_model(5, 5, 3, true, 0, Vec3(0, 0, 0));
  BackendTool tool{true, ToolMode::Pull, 0.02, 500.0};
  const GlBackendOptions options = recording();
  GlBackend gl(model, tool, options);
  const gl_test::MovingState s = gl_test::moving_state(model, kDt);
  gl.set_state(s.x, s.x_prev);
  // A top corner whose Kuhn corner point lies in one tet: light points with a
  // tool stiffness scale well below 1 (Model::tool_k_scale) are among those grasped.
  const Vec3 grasp(0.1, 0.0, 0.05);
  Attachment attachment;
  double smallest_scale = 1;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if ((model.rest_position[i] - grasp).norm() < 0.025) {
      attachment.points.push_back(i);
      attachment.offsets.push_back(model.rest_position[i] - grasp);
      smallest_scale = std::min(smallest_scale, model.tool_scale(i));
    }
  }
  ASSERT_GT(attachment.points.size(), 3u);
  ASSERT_LT(smallest_scale, 0.5);
  gl.attach(attachment);
  const Vec3 center = grasp + Vec3(0.003, -0.002, 0.01);  // dragged up and sideways: force and torque
  TickRequest request = testing::one_step_at(kDt, center);
  gl.tick(request);
  std::vector<Vec3> got, want;
  gl.forces(got);
  reference_internal_forces(model, s.x, s.v, want);
  const Reaction expect = reference_pull_forces(s.x, attachment, center, tool.contact_stiffness, want, model.tool_k_scale);
  EXPECT_LT(relative_difference(got, want), 1e-5);
  request.tool_active = false;
  const Reaction r = gl.tick(request);
  EXPECT_EQ(r.contacts, static_cast<int32_t>(attachment.points.size()));
  EXPECT_LT((r.force - expect.force).norm(), 1e-5 * expect.force.norm());
  ASSERT_GT(expect.torque.norm(), 0);
  // Torque: lever arms ~2 cm times float-rounded forces.
  EXPECT_LT((r.torque - expect.torque).norm(), 1e-5 * expect.force.norm() * 0.03);
  std::cout << "pull reaction " << r.force.transpose() << " N / torque " << r.torque.transpose() << " N m\n";

  // After release the attachment springs are gone.
  gl.release();
  request.tool_active = true;
  gl.tick(request);
  request.tool_active = false;
  EXPECT_EQ(gl.tick(request).contacts, 0);
}

TEST_P(GlKernel, BindingsAndWorkgroupSizeAgreeBetweenCppAndGlsl) {
  const Model model = gl_test::box_model(2, 2, 2, true, 1e4, Vec3(0, 0, -9.81));
  GlBackend gl(model, BackendTool{true, ToolMode::Pull, 0.01, 100.0}, recording());
  EXPECT_EQ(gl.threads_per_point(), GetParam());
  // Compile the full variant and ask the driver what the GLSL declared.
  gl::ComputeProgram step("step.comp", {"HAS_VOLUME", "HAS_GRAVITY", "TOOL_PULL", "RECORD_FORCE",
                                        "THREADS_PER_POINT " + std::to_string(GetParam())});
  EXPECT_EQ(step.workgroup_size()[0], ORGANSIM_GL_CHUNK * GetParam());
  EXPECT_EQ(ORGANSIM_GL_CHUNK, model.layout.chunk_size);
  EXPECT_EQ(step.storage_block_binding("XCur"), ORGANSIM_GL_B_X_CUR);
  EXPECT_EQ(step.storage_block_binding("DCur"), ORGANSIM_GL_B_D_CUR);
  EXPECT_EQ(step.storage_block_binding("XNext"), ORGANSIM_GL_B_X_NEXT);
  EXPECT_EQ(step.storage_block_binding("DNext"), ORGANSIM_GL_B_D_NEXT);
  EXPECT_EQ(step.storage_block_binding("Mass"), ORGANSIM_GL_B_MASS);
  EXPECT_EQ(step.storage_block_binding("Chunks"), ORGANSIM_GL_B_CHUNKS);
  EXPECT_EQ(step.storage_block_binding("Springs"), ORGANSIM_GL_B_SPRINGS);
  EXPECT_EQ(step.storage_block_binding("Tets"), ORGANSIM_GL_B_TETS);
  EXPECT_EQ(step.storage_block_binding("Attach"), ORGANSIM_GL_B_ATTACH);
  EXPECT_EQ(step.storage_block_binding("Partials"), ORGANSIM_GL_B_PARTIALS);
  EXPECT_EQ(step.storage_block_binding("Force"), ORGANSIM_GL_B_FORCE);
  EXPECT_EQ(step.storage_block_binding("Status"), ORGANSIM_GL_B_STATUS);
  // std430 strides of the entry structs equal the C++ packing (16 and 20 bytes).
  const GLenum stride = GL_TOP_LEVEL_ARRAY_STRIDE;
  GLint spring_stride = 0, tet_stride = 0;
  glGetProgramResourceiv(step.id(), GL_BUFFER_VARIABLE,
                         glGetProgramResourceIndex(step.id(), GL_BUFFER_VARIABLE, "springs[0].other"), 1,
                         &stride, 1, nullptr, &spring_stride);
  glGetProgramResourceiv(step.id(), GL_BUFFER_VARIABLE,
                         glGetProgramResourceIndex(step.id(), GL_BUFFER_VARIABLE, "tets[0].a"), 1, &stride, 1,
                         nullptr, &tet_stride);
  EXPECT_EQ(spring_stride, 16);
  EXPECT_EQ(tet_stride, 20);
  // A lean variant has no volume, tool or force blocks at all.
  gl::ComputeProgram lean("step.comp", {});
  EXPECT_EQ(lean.storage_block_binding("Tets"), -1);
  EXPECT_EQ(lean.storage_block_binding("Partials"), -1);
  gl.context().check_errors("binding queries");
}

INSTANTIATE_TEST_SUITE_P(ThreadsPerPoint, GlKernel, ::testing::Values(1, 3, 8),
                         [](const ::testing::TestParamInfo<int32_t>& info) { return std::to_string(info.param); });

TEST(GlBackendOptions, ThreadsPerPointOutsideOneToSixteenIsAUsageError) {
  const Model model = gl_test::box_model(2, 2, 2, true, 0, Vec3(0, 0, 0));
  for (const int32_t bad : {-1, 17}) {
    GlBackendOptions options;
    options.threads_per_point = bad;
    try {
      GlBackend gl(model, BackendTool{}, options);
      ADD_FAILURE() << "threads_per_point " << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Usage);
      EXPECT_NE(std::string(e.what()).find("1 to 16"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace kernel_test
}  // namespace organsim
