#pragma once
// Helpers shared by the render tests: meshes, pixel statistics, projection.
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <vector>

#include "core/mesh/tet_mesh.h"
#include "core/model/model.h"
#include "core/render/camera.h"

namespace organsim::testing {

// A 20 x 20 cm slab of height `top` (m), n x n x 2 cells, held at its base:
// the model the frame tests press a tool into.
inline Model pressed_slab_model(int n, double top) {
  const TetMesh mesh = make_box_tet_mesh(Vec3(-0.1, -0.1, 0), Vec3(0.1, 0.1, top), n, n, 2);
  ModelOptions options;
  FixedSelector bottom;
  bottom.kind = FixedSelector::Kind::Box;
  bottom.min = Vec3(-1, -1, -1e-3);
  bottom.max = Vec3(1, 1, 1e-3);
  options.fixed.push_back(bottom);
  return build_model(mesh, Material{}, options, "slab");
}

// UV sphere surface, outward counter-clockwise.
inline TriangleMesh uv_sphere(const Vec3& center, double radius, int slices = 32, int stacks = 16) {
  TriangleMesh m;
  m.points.push_back(center + Vec3(0, 0, radius));
  for (int i = 1; i < stacks; ++i) {
    const double th = std::numbers::pi * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double ph = 2 * std::numbers::pi * j / slices;
      m.points.push_back(center + radius * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  }
  m.points.push_back(center + Vec3(0, 0, -radius));
  const int south = static_cast<int>(m.points.size()) - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * slices + (j % slices); };
  for (int j = 0; j < slices; ++j) m.faces.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i < stacks - 1; ++i) {
    for (int j = 0; j < slices; ++j) {
      m.faces.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.faces.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  }
  for (int j = 0; j < slices; ++j) m.faces.push_back({south, ring(stacks - 1, j + 1), ring(stacks - 1, j)});
  return m;
}

// Pixels whose colour differs from `bgr` by more than `tolerance` in any channel.
inline cv::Mat differs_from(const cv::Mat& image, const cv::Vec3b& bgr, int tolerance) {
  cv::Mat diff;
  cv::absdiff(image, cv::Scalar(bgr[0], bgr[1], bgr[2]), diff);
  std::vector<cv::Mat> ch;
  cv::split(diff, ch);
  cv::Mat mx = cv::max(cv::max(ch[0], ch[1]), ch[2]);
  return mx > tolerance;
}

// Pixel of a world point (x right, y down from the top-left).
inline cv::Point2d project(const Camera& camera, const Vec3& p, int width, int height) {
  const Eigen::Vector4f clip = camera.projection(static_cast<double>(width) / height) * camera.view() *
                               Eigen::Vector4f(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                               static_cast<float>(p.z()), 1.0f);
  const double x = clip.x() / clip.w(), y = clip.y() / clip.w();
  return {(x + 1) / 2 * width, (1 - y) / 2 * height};
}

}  // namespace organsim::testing
