// With the GL backend the recorder draws straight from the simulation's
// position buffer (shared context, no copy through the CPU). The image must
// be the one the CPU upload path gives for the same state.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <utility>

#include "core/gl/gl_backend.h"
#include "core/model/model.h"
#include "core/render/frame_recorder.h"
#include "tests/render/render_test_util.h"

namespace organsim {
namespace gl_backend_frames_test {
namespace {

namespace fs = std::filesystem;

// Forwards to another backend but is not a GlBackend, so the recorder takes
// the CPU path (positions() + upload).
class HiddenBackend : public Backend {
 public:
  explicit HiddenBackend(Backend& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name(); }
  std::string device() const override { return inner_.device(); }
  std::string precision() const override { return inner_.precision(); }
  Plan plan() const override { return inner_.plan(); }
  const StepPlan& step_plan() const override { return inner_.step_plan(); }
  int32_t reaction_latency_ticks() const override { return inner_.reaction_latency_ticks(); }
  Reaction tick(const TickRequest& r) override { return inner_.tick(r); }
  void attach(const Attachment& a) override { inner_.attach(a); }
  void release() override { inner_.release(); }
  std::unique_ptr<PreparedModel> prepare(const Model& next) const override { return inner_.prepare(next); }
  void adopt(std::unique_ptr<PreparedModel> prepared) override { inner_.adopt(std::move(prepared)); }
  void positions(std::vector<Vec3>& out) const override { inner_.positions(out); }
  void set_state(const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev) override { inner_.set_state(x, x_prev); }
  double time() const override { return inner_.time(); }

 private:
  Backend& inner_;
};

cv::Mat first_frame(const fs::path& outdir) { return cv::imread((outdir / "frames" / "frame_00000.png").string()); }

// Frame 0 of `backend`'s current state drawn twice in `style`: straight from
// the GL backend's position buffer, and through the CPU upload path (the
// same backend hidden behind HiddenBackend). Returns the two images.
std::pair<cv::Mat, cv::Mat> direct_and_uploaded_frames(const Model& model, Backend& backend, const ToolSpec& tool,
                                                       const StyleOptions& style, const std::string& name) {
  FrameOutputs outputs;
  FramesOptions frames;
  frames.width = 200;
  frames.height = 150;
  frames.style = style;
  outputs.frames = frames;
  const fs::path direct_dir = fs::path(ORGANSIM_TEST_TMP) / (name + "_direct");
  const fs::path upload_dir = fs::path(ORGANSIM_TEST_TMP) / (name + "_upload");
  fs::remove_all(direct_dir);
  fs::remove_all(upload_dir);
  {
    auto direct = make_frame_recorder(outputs, direct_dir, 0.0, tool);
    direct->on_start(model, backend);  // renders frame 0 from the GL buffer
    direct->on_finish(model, backend);
  }
  HiddenBackend hidden(backend);
  {
    auto upload = make_frame_recorder(outputs, upload_dir, 0.0, tool);
    upload->on_start(model, hidden);
    upload->on_finish(model, hidden);
  }
  return {first_frame(direct_dir), first_frame(upload_dir)};
}

// Same float positions either way: identical up to rasterisation order (at
// most 1 level from a differently rounded normal in a few pixels).
double largest_difference(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  double max_diff = 0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &max_diff);
  return max_diff;
}

TEST(GlBackendFrames, DrawingFromTheSimulationBufferMatchesTheUploadPath) {
  const double top = 0.04, radius = 0.015;
  const Model model = testing::pressed_slab_model(8, top);
  ToolSpec tool;
  tool.radius = radius;
  tool.contact_stiffness = 500;
  tool.keyframes = {{0.0, Vec3(0, 0, top + radius + 0.002)}, {0.05, Vec3(0, 0, top + radius - 0.008)}};
  BackendTool backend_tool{true, ToolMode::Push, radius, tool.contact_stiffness};
  auto backend = make_gl_backend(model, backend_tool);

  TickRequest request;
  request.dt = 1e-4;
  request.substeps = 10;
  request.tool_active = true;
  for (int i = 0; i < 60; ++i) {
    request.tool_from = tool.position_at(i * 1e-3);
    request.tool_to = tool.position_at((i + 1) * 1e-3);
    backend->tick(request);
  }

  const auto [a, b] = direct_and_uploaded_frames(model, *backend, tool, StyleOptions{}, "gl");
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  EXPECT_LE(largest_difference(a, b), 2.0);

  // The dent is there: the model is not at rest (the pressed slab differs
  // from the rest shape somewhere, i.e. the buffer is the live x_t).
  std::vector<Vec3> x;
  backend->positions(x);
  double moved = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) moved = std::max(moved, (x[i] - model.rest_position[i]).norm());
  EXPECT_GT(moved, 2e-3);  // the tool is 8 mm deep; the top moves millimetres

  // The simulation keeps running in its own context after the recorder drew.
  request.tool_from = request.tool_to;
  const Reaction r = backend->tick(request);
  EXPECT_TRUE(r.force.allFinite());
  backend->positions(x);
  for (const Vec3& p : x) ASSERT_TRUE(p.allFinite());
}

// Labels from the GL buffer: each triangle's colour is found by its index
// in the draw (gl_PrimitiveID), whichever buffer the positions come from. A
// slab whose x > 0 half is label 2: both paths give the same image, and it
// shows both labels' colours.
TEST(GlBackendFrames, LabelColoursFromTheSimulationBufferMatchTheUploadPath) {
  TetMesh mesh = make_box_tet_mesh(Vec3(-0.1, -0.1, 0), Vec3(0.1, 0.1, 0.04), 8, 8, 2);
  for (const Tet& t : mesh.tets) {
    const double x = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]] + mesh.points[t[3]]).x() / 4;
    mesh.labels.push_back(x < 0 ? 1 : 2);
  }
  const Model model = build_model(mesh, Material{}, ModelOptions{}, "two-label slab");
  auto backend = make_gl_backend(model, BackendTool{});
  StyleOptions style;
  style.colormap = Colormap::Label;
  const auto [a, b] = direct_and_uploaded_frames(model, *backend, ToolSpec{}, style, "gl_labels");
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  EXPECT_LE(largest_difference(a, b), 2.0);
  // Orange (label 1: red well above blue) and sky blue (label 2: blue above red) both cover ground.
  int orange = 0, blue = 0;
  for (int v = 0; v < a.rows; ++v) {
    for (int u = 0; u < a.cols * 3 / 4; ++u) {  // left of the key
      const cv::Vec3b c = a.at<cv::Vec3b>(v, u);
      orange += c[2] > c[0] + 80;
      blue += c[0] > c[2] + 60;
    }
  }
  EXPECT_GT(orange, 500);
  EXPECT_GT(blue, 500);
}

}  // namespace
}  // namespace gl_backend_frames_test
}  // namespace organsim
