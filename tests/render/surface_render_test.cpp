// The renderer on the headless EGL context (llvmpipe in CI). No skips: when
// no context can be made the test fails with the EGL call and error code.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "core/gl/egl_context.h"
#include "core/mesh/boundary.h"
#include "core/render/camera.h"
#include "core/render/surface_renderer.h"
#include "tests/render/render_test_util.h"

namespace organsim {
namespace surface_render_test {
namespace {

using testing::differs_from;
using testing::project;
using testing::uv_sphere;

TEST(Camera, TargetProjectsToTheImageCentreAndAutoFitKeepsTheBoxInView) {
  CameraOptions options;
  options.auto_fit = false;
  options.position = Vec3(0.3, -0.2, 0.25);
  options.target = Vec3(0.01, 0.02, 0.03);
  const std::vector<Vec3> box = {{-0.05, -0.04, -0.03}, {0.06, 0.05, 0.04}};
  const Camera cam = make_camera(options, box, 4.0 / 3.0);
  const cv::Point2d c = project(cam, options.target, 400, 300);
  // float matrices: ~1e-4 px.
  EXPECT_NEAR(c.x, 200.0, 1e-3);
  EXPECT_NEAR(c.y, 150.0, 1e-3);

  CameraOptions fit;  // auto
  for (double aspect : {0.5, 1.0, 2.0}) {
    const Camera a = make_camera(fit, box, aspect);
    const int w = static_cast<int>(300 * aspect), h = 300;
    for (int k = 0; k < 8; ++k) {
      const Vec3 corner((k & 1) ? box[1].x() : box[0].x(), (k & 2) ? box[1].y() : box[0].y(),
                        (k & 4) ? box[1].z() : box[0].z());
      const cv::Point2d p = project(a, corner, w, h);
      EXPECT_GT(p.x, 0);
      EXPECT_LT(p.x, w);
      EXPECT_GT(p.y, 0);
      EXPECT_LT(p.y, h);
    }
  }
}

TEST(SurfaceRenderer, SphereFillsTheCentreAndLeavesCornersBackground) {
  gl::EglContext context;
  const int width = 200, height = 150;
  SurfaceRenderer renderer(width, height);
  const TriangleMesh sphere = uv_sphere(Vec3(0.1, 0.2, 0.3), 0.05);
  renderer.set_faces(sphere.faces, static_cast<int32_t>(sphere.points.size()));
  renderer.set_positions(sphere.points);
  CameraOptions options;
  options.auto_fit = false;
  options.target = Vec3(0.1, 0.2, 0.3);
  options.position = options.target + Vec3(0.0, -0.4, 0.1);
  options.fov_deg = 30;
  const Camera cam = make_camera(options, sphere.points, static_cast<double>(width) / height);
  StyleOptions style;
  style.background = Vec3(0.0, 0.0, 1.0);  // pure blue: BGR (255, 0, 0)
  const cv::Mat image = renderer.render(cam, style, {});
  ASSERT_EQ(image.cols, width);
  ASSERT_EQ(image.rows, height);
  ASSERT_EQ(image.type(), CV_8UC3);
  const cv::Mat object = differs_from(image, cv::Vec3b(255, 0, 0), 8);
  // The sphere (radius 0.05 m at 0.41 m, fov 30 deg) spans ~2*7 deg of 30:
  // ~0.45 of the height, a disc of ~34 px radius. Its centre 15x15 px block
  // is all object, the four 20x20 corners all background.
  EXPECT_EQ(cv::countNonZero(object(cv::Rect(width / 2 - 7, height / 2 - 7, 15, 15))), 15 * 15);
  for (const cv::Point corner : {cv::Point(0, 0), cv::Point(width - 20, 0), cv::Point(0, height - 20),
                                 cv::Point(width - 20, height - 20)}) {
    EXPECT_EQ(cv::countNonZero(object(cv::Rect(corner.x, corner.y, 20, 20))), 0) << corner;
  }
  // Area of the disc within 25 % of pi r^2 (r from the projection; the
  // polygonal sphere and the perspective make it approximate).
  const cv::Point2d centre = project(cam, options.target, width, height);
  const cv::Point2d rim = project(cam, options.target + Vec3(0.05, 0, 0), width, height);
  const double r = std::hypot(rim.x - centre.x, rim.y - centre.y);
  EXPECT_NEAR(cv::countNonZero(object), std::numbers::pi * r * r, 0.25 * std::numbers::pi * r * r);
  // Lit: the centre faces the headlight and is brighter than the rim.
  const cv::Vec3b mid = image.at<cv::Vec3b>(height / 2, width / 2);
  const cv::Vec3b edge = image.at<cv::Vec3b>(height / 2, static_cast<int>(centre.x + 0.85 * r));
  EXPECT_GT(mid[2], edge[2]);

  // Looking away from the sphere: nothing but background.
  options.target = options.position + Vec3(0, 0.4, 0.8);
  const cv::Mat away = renderer.render(make_camera(options, sphere.points, 4.0 / 3.0), style, {});
  EXPECT_EQ(cv::countNonZero(differs_from(away, cv::Vec3b(255, 0, 0), 8)), 0);
  context.check_errors("after rendering");
}

TEST(SurfaceRenderer, WireframeAndToolAddPixels) {
  gl::EglContext context;
  SurfaceRenderer renderer(160, 120);
  const TetMesh box = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), 3, 3, 3);
  renderer.set_faces(extract_boundary_faces(box.tets), static_cast<int32_t>(box.points.size()));
  renderer.set_positions(box.points);
  const Camera cam = make_camera(CameraOptions{}, box.points, 160.0 / 120.0);
  StyleOptions style;
  const cv::Mat plain = renderer.render(cam, style, {});
  style.wireframe = true;
  const cv::Mat wire = renderer.render(cam, style, {});
  // Edge lines are dark (0.12 grey): many more near-black pixels with them.
  const auto dark = [](const cv::Mat& m) {
    cv::Mat grey;
    cv::cvtColor(m, grey, cv::COLOR_BGR2GRAY);
    return cv::countNonZero(grey < 45);
  };
  EXPECT_GT(dark(wire), dark(plain) + 200);
  // The tool sphere next to the box adds object pixels.
  style.wireframe = false;
  const Vec3 centre(0.05, 0.05, 0.13);
  const cv::Mat with_tool = renderer.render(cam, style, ToolDraw{true, centre, centre, 0.02});
  const auto object = [&](const cv::Mat& m) { return cv::countNonZero(differs_from(m, cv::Vec3b(255, 255, 255), 8)); };
  EXPECT_GT(object(with_tool), object(plain) + 100);
  // A capsule of the same radius with a 6 cm shaft across the view adds its
  // shaft: clearly more pixels than the sphere (a capsule drawn as its
  // sphere, or with the shaft collapsed, would not).
  const cv::Mat with_capsule =
      renderer.render(cam, style, ToolDraw{true, centre - Vec3(0.03, 0, 0), centre + Vec3(0.03, 0, 0), 0.02});
  EXPECT_GT(object(with_capsule), object(with_tool) + 300);
  // A grasper's two jaws: that capsule and a second one 9 cm beside it (in
  // view, clear of the first and of the box) add the second's own pixels (a
  // second jaw not drawn would not).
  const Vec3 shift(0.09, 0, 0);
  const ToolDraw second{true, centre - Vec3(0.03, 0, 0) + shift, centre + Vec3(0.03, 0, 0) + shift, 0.02};
  const int alone = object(renderer.render(cam, style, second)) - object(plain);
  ASSERT_GT(alone, 300) << "the second jaw must be in view";
  ToolDraw jaws{true, centre - Vec3(0.03, 0, 0), centre + Vec3(0.03, 0, 0), 0.02};
  jaws.segments = 2;
  jaws.a2 = second.a, jaws.b2 = second.b;
  EXPECT_GT(object(renderer.render(cam, style, jaws)), object(with_capsule) + alone / 3);
}

}  // namespace
}  // namespace surface_render_test
}  // namespace organsim
