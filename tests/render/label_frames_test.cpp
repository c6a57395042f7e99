// Frames coloured by label (style.colormap "label"), checked on pixels: a box
// whose inner 5 cm cube is label 2 and the rest label 1. From outside only
// label 1 shows; after a cut through the middle, with the far half moved out
// of view, the cut face shows label 2 in its centre, label 1 around it and a
// dark line where they meet: the recorder re-extracts the boundary and its
// faces' labels after the rebuild.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/mesh/boundary.h"
#include "core/model/model.h"
#include "core/model/model_rebuild.h"
#include "core/render/camera.h"
#include "core/render/frame_recorder.h"
#include "core/render/label_colors.h"
#include "core/sim/cpu_backend.h"
#include "tests/core/test_models.h"
#include "tests/render/render_test_util.h"

namespace organsim {
namespace label_frames_test {
namespace {

namespace fs = std::filesystem;
using testing::project;

constexpr int kWidth = 320, kHeight = 240;

// 10 cm box in 4 x 4 x 4 cells of 2.5 cm; the inner 2 x 2 x 2 cells are label 2.
Model two_label_box() {
  TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), 4, 4, 4);
  for (const Tet& tet : mesh.tets) {
    Vec3 c = Vec3::Zero();
    for (int32_t p : tet) c += mesh.points[p] / 4;
    const bool inner = (c.array() > 0.025).all() && (c.array() < 0.075).all();
    mesh.labels.push_back(inner ? 2 : 1);
  }
  return build_model(mesh, Material{}, ModelOptions{}, "two-label box");
}

// Which label's colour a pixel shows: orange (label 1) is red-heavy, sky
// blue (label 2) blue-heavy; shading scales both channels alike and the
// specular highlight adds the same to each, so the difference keeps its sign.
bool looks_like_label_1(const cv::Vec3b& bgr) { return bgr[2] > bgr[0] + 80; }
bool looks_like_label_2(const cv::Vec3b& bgr) { return bgr[0] > bgr[2] + 60; }
bool dark(const cv::Vec3b& bgr) { return bgr[0] < 60 && bgr[1] < 60 && bgr[2] < 60; }

TEST(LabelFrames, LabelColoursAndTheirBoundaryFollowACut) {
  ASSERT_TRUE(looks_like_label_1(cv::Vec3b(0, 159, 230)));  // the palette's own colours, BGR
  ASSERT_TRUE(looks_like_label_2(cv::Vec3b(233, 180, 86)));
  const Model model = two_label_box();
  auto backend = make_cpu_backend(model, BackendTool{}, {Precision::Double, 1});  // one thread: no timing at construction
  const fs::path outdir = fs::path(ORGANSIM_TEST_TMP) / ("label_frames_" + std::to_string(::getpid()));
  fs::remove_all(outdir);

  FramesOptions frames;
  frames.rate = 1;  // frame 0 at t = 0, frame 1 at t = 1
  frames.width = kWidth;
  frames.height = kHeight;
  frames.style.colormap = Colormap::Label;
  // Looking at the x = 0.1 face from +x, and after the cut at the left half's cut face.
  frames.camera.auto_fit = false;
  frames.camera.position = Vec3(0.4, 0.05, 0.05);
  frames.camera.target = Vec3(0.05, 0.05, 0.05);
  frames.camera.fov_deg = 30;
  FrameOutputs outputs;
  outputs.frames = frames;
  auto recorder = make_frame_recorder(outputs, outdir, 1.0, std::nullopt);
  ASSERT_NE(recorder, nullptr);
  recorder->on_start(model, *backend);

  // Through cut at x = 0.05 (a plane of tet faces), then the far half (x >
  // 0.05, with its own copies of the plane's points) moved 1 m aside.
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.05));
  backend->rebuild(cut);
  std::vector<Vec3> x;
  backend->positions(x);
  std::vector<bool> far(cut.npoint(), false);
  for (const Tet& tet : cut.tet_points) {
    Vec3 c = Vec3::Zero();
    for (int32_t p : tet) c += cut.rest_position[p] / 4;
    if (c.x() > 0.05) for (int32_t p : tet) far[p] = true;
  }
  for (int32_t p = 0; p < cut.npoint(); ++p) {
    if (far[p]) x[p] += Vec3(0, 1, 0);
  }
  backend->set_state(x, x);
  recorder->on_topology_changed(cut, *backend);
  TickInfo info;
  info.t = 1.0;
  recorder->on_tick(cut, *backend, info);
  recorder->on_finish(cut, *backend);

  const cv::Mat outside = cv::imread((outdir / "frames" / "frame_00000.png").string());
  const cv::Mat opened = cv::imread((outdir / "frames" / "frame_00001.png").string());
  ASSERT_FALSE(outside.empty());
  ASSERT_FALSE(opened.empty());
  const Camera cam = make_camera(frames.camera, model.rest_position, static_cast<double>(kWidth) / kHeight);
  const auto pixel = [&](const cv::Mat& image, const Vec3& p) {
    const cv::Point2d px = project(cam, p, kWidth, kHeight);
    return image.at<cv::Vec3b>(static_cast<int>(px.y), static_cast<int>(px.x));
  };

  // Outside: the x = 0.1 face is label 1 all over, no label 2 anywhere in
  // the square it covers (the key on the right edge is outside that square).
  const cv::Point2d lo = project(cam, Vec3(0.1, 0.005, 0.095), kWidth, kHeight);
  const cv::Point2d hi = project(cam, Vec3(0.1, 0.095, 0.005), kWidth, kHeight);
  int label_1 = 0, label_2 = 0, total = 0;
  for (int v = static_cast<int>(lo.y); v <= static_cast<int>(hi.y); ++v) {
    for (int u = static_cast<int>(lo.x); u <= static_cast<int>(hi.x); ++u) {
      const cv::Vec3b c = outside.at<cv::Vec3b>(v, u);
      label_1 += looks_like_label_1(c);
      label_2 += looks_like_label_2(c);
      ++total;
    }
  }
  EXPECT_GT(total, 1000);
  EXPECT_GT(label_1, total * 9 / 10);
  EXPECT_EQ(label_2, 0);

  // The cut face at x = 0.05: label 2 in the middle 5 cm square, label 1 in
  // the 2.5 cm ring around it, each well inside its region (half a cell from
  // the boundary, clear of the line).
  for (const Vec3& p : {Vec3(0.05, 0.05, 0.05), Vec3(0.05, 0.035, 0.065), Vec3(0.05, 0.065, 0.035)}) {
    EXPECT_TRUE(looks_like_label_2(pixel(opened, p))) << p.transpose() << ": " << pixel(opened, p);
  }
  for (const Vec3& p : {Vec3(0.05, 0.0125, 0.05), Vec3(0.05, 0.0875, 0.05), Vec3(0.05, 0.05, 0.0125),
                        Vec3(0.05, 0.05, 0.0875)}) {
    EXPECT_TRUE(looks_like_label_1(pixel(opened, p))) << p.transpose() << ": " << pixel(opened, p);
  }
  // The line where the labels meet: across the boundary at y = 0.025 (from
  // y = 0.02 to 0.03, a few pixels), some pixel is dark, for each of three
  // heights; inside a region (y = 0.04 to 0.05) none is.
  for (double z : {0.035, 0.05, 0.065}) {
    const cv::Point2d a = project(cam, Vec3(0.05, 0.02, z), kWidth, kHeight);
    const cv::Point2d b = project(cam, Vec3(0.05, 0.03, z), kWidth, kHeight);
    const cv::Point2d c = project(cam, Vec3(0.05, 0.04, z), kWidth, kHeight);
    const cv::Point2d d = project(cam, Vec3(0.05, 0.05, z), kWidth, kHeight);
    const int v = static_cast<int>(a.y);
    int dark_across = 0, dark_inside = 0;
    for (int u = static_cast<int>(a.x); u <= static_cast<int>(b.x); ++u) dark_across += dark(opened.at<cv::Vec3b>(v, u));
    for (int u = static_cast<int>(c.x); u <= static_cast<int>(d.x); ++u) dark_inside += dark(opened.at<cv::Vec3b>(v, u));
    EXPECT_GT(dark_across, 0) << "z = " << z;
    EXPECT_EQ(dark_inside, 0) << "z = " << z;
  }
}

TEST(LabelFrames, PaletteIsFixedAndDistinct) {
  // Labels 1..7 are seven different colours, label 8 repeats label 1, and
  // label 0 (unlabelled) is grey.
  for (int32_t a = 1; a <= 7; ++a) {
    for (int32_t b = a + 1; b <= 7; ++b) EXPECT_GT((label_rgb(a) - label_rgb(b)).norm(), 0.2f) << a << " " << b;
  }
  EXPECT_EQ(label_rgb(8), label_rgb(1));
  EXPECT_FLOAT_EQ(label_rgb(0).x(), label_rgb(0).z());
}

TEST(LabelFrames, EdgesBetweenFaceGroupsAreWhereTheGroupsMeet) {
  // Two triangles sharing edge (1, 2): one edge between them only when their groups differ.
  const std::vector<Tri> faces = {{0, 1, 2}, {2, 1, 3}};
  EXPECT_EQ(edges_between_face_groups(faces, {1, 2}), (std::vector<Edge>{{1, 2}}));
  EXPECT_TRUE(edges_between_face_groups(faces, {4, 4}).empty());
  std::vector<int32_t> owner;
  const std::vector<Tri> box = extract_boundary_faces({Tet{0, 1, 2, 3}, Tet{1, 2, 3, 4}}, &owner);
  ASSERT_EQ(owner.size(), box.size());
  for (size_t f = 0; f < box.size(); ++f) {
    const Tet& t = owner[f] == 0 ? Tet{0, 1, 2, 3} : Tet{1, 2, 3, 4};
    for (int32_t v : box[f]) EXPECT_NE(std::find(t.begin(), t.end(), v), t.end()) << "face " << f;
  }
}

}  // namespace
}  // namespace label_frames_test
}  // namespace organsim
