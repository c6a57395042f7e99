#pragma once
// Look-at camera and perspective projection as 4x4 matrices (OpenGL
// conventions: right-handed eye space looking down -z, clip z in [-w, w]).
#include <Eigen/Core>
#include <vector>

#include "core/render/frame_options.h"

namespace organsim {

struct Camera {
  Vec3 position{0, 0, 1}, target{0, 0, 0}, up{0, 0, 1};  // m
  double fov_deg = 35.0;  // vertical
  double near_plane = 0.01, far_plane = 10.0;  // m, distances along the view
  Eigen::Matrix4f view() const;
  Eigen::Matrix4f projection(double aspect) const;  // aspect = width / height
};

// Resolves options into a camera. Auto-fit frames the axis-aligned bounding
// box of `points` (its bounding sphere fills the smaller field of view with
// a 10 % margin). Near and far planes always enclose that sphere.
// Throws Error(Scenario) for a degenerate camera (eye at target, up parallel
// to the view, fov outside (0, 180)).
Camera make_camera(const CameraOptions& options, const std::vector<Vec3>& points, double aspect);

// The camera for a run. With auto_fit it frames the model and the tool's whole
// path (spheres of `tool_radius` about `tool_path`), looking from the side
// the tool comes from (its first position relative to the model's centre,
// raised 30 degrees above the horizontal plane of `up` and turned 30 degrees
// aside, so the contact is not hidden behind the tool). A tool that comes
// from straight above or below keeps the default oblique view.
Camera make_run_camera(const CameraOptions& options, const std::vector<Vec3>& points,
                       const std::vector<Vec3>& tool_path, double tool_radius, double aspect);

}  // namespace organsim
