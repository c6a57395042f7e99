// The run's camera frames the tool's whole path from the side the tool comes
// from, and the colour range is fixed before the run from the scenario or the
// tool's reach.
#include <gtest/gtest.h>

#include "core/render/camera.h"
#include "core/render/colormap_range.h"
#include "tests/render/render_test_util.h"

namespace organsim {
namespace run_camera_test {
namespace {

// A long thin organ along x, 20 x 4 x 4 cm, as a cloud of its box corners and centre.
std::vector<Vec3> organ_along_x() {
  std::vector<Vec3> p;
  for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? 0.1 : -0.1, i & 2 ? 0.02 : -0.02, i & 4 ? 0.02 : -0.02);
  p.emplace_back(0, 0, 0);
  return p;
}

bool inside_image(const Camera& camera, const Vec3& p, int width, int height) {
  const cv::Point2d px = testing::project(camera, p, width, height);
  return px.x >= 0 && px.x <= width && px.y >= 0 && px.y <= height;
}

TEST(RunCamera, LooksFromTheSideTheToolComesFromAndFramesItsPath) {
  const std::vector<Vec3> organ = organ_along_x();
  // Pushed from +y: from 10 cm away to 1 cm into the organ's side.
  const std::vector<Vec3> path = {{0.03, 0.13, 0.0}, {0.03, 0.07, 0.0}, {0.03, 0.029, 0.0}};
  const double radius = 0.01;
  const Camera camera = make_run_camera(CameraOptions{}, organ, path, radius, 640.0 / 480.0);
  EXPECT_GT(camera.position.y(), 0.1) << "the camera should be on the tool's (+y) side";
  EXPECT_GT(camera.position.z(), 0.0) << "and above the horizontal plane";
  // The documented up direction (+z) stays up in the image.
  const cv::Point2d low = testing::project(camera, Vec3(0, 0, -0.02), 640, 480);
  const cv::Point2d high = testing::project(camera, Vec3(0, 0, 0.02), 640, 480);
  EXPECT_LT(high.y, low.y);
  for (const Vec3& p : organ) EXPECT_TRUE(inside_image(camera, p, 640, 480));
  for (const Vec3& c : path) {
    for (const Vec3& d : {Vec3(radius, 0, 0), Vec3(0, radius, 0), Vec3(0, 0, radius)}) {
      EXPECT_TRUE(inside_image(camera, c + d, 640, 480) && inside_image(camera, c - d, 640, 480)) << c.transpose();
    }
  }
  // The old fixed view direction (1, -1.6, 0.9) put the camera on -y, behind the organ.
  const Camera fixed = make_camera(CameraOptions{}, organ, 640.0 / 480.0);
  EXPECT_LT(fixed.position.y(), 0.0);
}

TEST(RunCamera, ToolFromAboveKeepsTheDefaultObliqueView) {
  const std::vector<Vec3> organ = organ_along_x();
  const std::vector<Vec3> path = {{0.0, 0.0, 0.1}, {0.0, 0.0, 0.03}};
  const Camera run = make_run_camera(CameraOptions{}, organ, path, 0.01, 4.0 / 3.0);
  const Vec3 direction = (run.position - run.target).normalized();
  EXPECT_NEAR(direction.dot(CameraOptions{}.auto_direction.normalized()), 1.0, 1e-9);
}

TEST(ColormapRange, FixedFromTheScenarioOrEstimatedFromTheToolsReach) {
  // A flat grid of points at z = 0, 1 cm apart; a 1 cm sphere pushed 4 mm
  // below the surface over the first half of a 1 s run, then held.
  std::vector<Vec3> start;
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j) start.emplace_back(0.01 * i, 0.01 * j, 0.0);
  ToolSpec tool;
  tool.radius = 0.01;
  tool.keyframes = {{0.0, Vec3(0, 0, 0.02)}, {0.5, Vec3(0, 0, 0.006)}};
  // The deepest the sphere reaches below the grid point under its centre:
  // 1 cm - 6 mm = 4 mm; sampled every 5 ms, so exact at the held end.
  EXPECT_NEAR(tool_reach(tool, start, 1.0), 0.004, 1e-12);

  StyleOptions style;
  style.colormap = Colormap::Displacement;
  ColormapRange r = colormap_range(style, tool, start, 1.0);
  EXPECT_NEAR(r.max, 0.004, 1e-12);
  EXPECT_EQ(colormap_legend_title(Colormap::Displacement, r), "displacement (fixed, estimate)");
  style.colormap = Colormap::Strain;
  EXPECT_NEAR(colormap_range(style, tool, start, 1.0).max, 0.4, 1e-9);  // reach / radius
  style.colormap_max = 0.25;
  r = colormap_range(style, tool, start, 1.0);
  EXPECT_EQ(r.max, 0.25);
  EXPECT_EQ(r.source, "scenario");
  // No tool: the first frame with a value will set it.
  style.colormap_max = 0;
  EXPECT_EQ(colormap_range(style, std::nullopt, start, 1.0).max, 0.0);

  // A pulling tool grasping at 0.2 s and travelling 3 cm: reach 3 cm.
  tool.mode = ToolMode::Pull;
  tool.grasp_time = 0.2;
  tool.keyframes = {{0.0, Vec3(0, 0, 0)}, {0.2, Vec3(0, 0, 0)}, {0.8, Vec3(0, 0, 0.03)}};
  EXPECT_NEAR(tool_reach(tool, start, 1.0), 0.03, 1e-12);
}

}  // namespace
}  // namespace run_camera_test
}  // namespace organsim
