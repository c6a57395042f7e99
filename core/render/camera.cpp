#include "core/render/camera.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/util/error.h"

namespace organsim {

namespace {
double radians(double deg) { return deg * std::numbers::pi / 180.0; }
}  // namespace

Eigen::Matrix4f Camera::view() const {
  const Vec3 f = (target - position).normalized();
  const Vec3 s = f.cross(up).normalized();
  const Vec3 u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(position);
  m(1, 3) = -u.dot(position);
  m(2, 3) = f.dot(position);
  return m.cast<float>();
}

Eigen::Matrix4f Camera::projection(double aspect) const {
  const double t = 1.0 / std::tan(radians(fov_deg) / 2);
  const double n = near_plane, f = far_plane;
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = -(f + n) / (f - n);
  m(2, 3) = -2 * f * n / (f - n);
  m(3, 2) = -1;
  return m.cast<float>();
}

Camera make_camera(const CameraOptions& options, const std::vector<Vec3>& points, double aspect) {
  if (!(options.fov_deg > 0 && options.fov_deg < 180)) {
    throw Error(ErrorKind::Scenario, "camera.fov_deg: expected a value in (0, 180) degrees, got " +
                                         std::to_string(options.fov_deg));
  }
  Vec3 lo = Vec3::Constant(0), hi = Vec3::Constant(0);
  if (!points.empty()) {
    lo = hi = points[0];
    for (const Vec3& p : points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const Vec3 center = (lo + hi) / 2;
  const double radius = std::max((hi - lo).norm() / 2, 1e-6);

  Camera cam;
  cam.fov_deg = options.fov_deg;
  cam.up = options.up;
  if (options.auto_fit) {
    // The sphere fits when distance * sin(half angle) = radius; use the
    // smaller of the vertical and horizontal half angles.
    const double half_v = radians(options.fov_deg) / 2;
    const double half_h = std::atan(std::tan(half_v) * aspect);
    const double half = std::min(half_v, half_h);
    const double distance = 1.1 * radius / std::sin(half);
    cam.target = center;
    cam.position = center + options.auto_direction.normalized() * distance;
  } else {
    cam.position = options.position;
    cam.target = options.target_at_center ? center : options.target;
  }
  const Vec3 view = cam.target - cam.position;
  if (view.norm() <= 0) throw Error(ErrorKind::Scenario, "camera: position equals target");
  if (view.normalized().cross(cam.up.normalized()).norm() < 1e-6) {
    throw Error(ErrorKind::Scenario, "camera.up: parallel to the viewing direction");
  }
  // Depth range enclosing the model's bounding sphere (and the tool near it);
  // clamp near so the depth buffer keeps its precision.
  const double along = (center - cam.position).dot(view.normalized());
  cam.far_plane = std::max(along + 3 * radius, 1e-3);
  cam.near_plane = std::max(along - 3 * radius, cam.far_plane * 1e-3);
  return cam;
}

Camera make_run_camera(const CameraOptions& options, const std::vector<Vec3>& points,
                       const std::vector<Vec3>& tool_path, double tool_radius, double aspect) {
  if (!options.auto_fit || tool_path.empty()) return make_camera(options, points, aspect);
  std::vector<Vec3> framed = points;
  for (const Vec3& c : tool_path) {
    for (int axis = 0; axis < 3; ++axis) {
      framed.push_back(c + tool_radius * Vec3::Unit(axis));
      framed.push_back(c - tool_radius * Vec3::Unit(axis));
    }
  }
  Vec3 lo = points.empty() ? Vec3::Zero() : points[0], hi = lo;
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 up = options.up.normalized();
  const Vec3 from_model = tool_path.front() - (lo + hi) / 2;
  const Vec3 across = from_model - from_model.dot(up) * up;  // the tool's side in the horizontal plane
  CameraOptions o = options;
  // Within ~25 degrees of straight above/below: the default oblique view shows it.
  if (across.norm() > 0.45 * from_model.norm()) {
    const Vec3 side = across.normalized();
    const Vec3 aside = up.cross(side);
    const double turn = std::numbers::pi / 6, raise = std::numbers::pi / 6;
    o.auto_direction = std::cos(raise) * (std::cos(turn) * side + std::sin(turn) * aside) + std::sin(raise) * up;
  }
  return make_camera(o, framed, aspect);
}

}  // namespace organsim
