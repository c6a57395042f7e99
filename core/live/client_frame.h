#pragma once
// How a live client's tool pose becomes the tool centre in the scene: the
// client's length unit (3D Slicer and most trackers send millimetres) and a
// rigid 4x4 matrix from the client's frame to the scene's
// (`--client-units`, `--client-transform`, docs/live.md). Replies go the
// other way: force and torque are turned into the client's frame.
#include <Eigen/Dense>

#include <array>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

using Matrix4 = Eigen::Matrix4d;

struct ClientFrame {
  double metres_per_unit = 1e-3;            // the client's length unit in m (mm by default)
  Matrix4 to_scene = Matrix4::Identity();   // client frame -> scene frame, translation in client units

  // The scene position (m) of the origin of a pose matrix (row-major 4x4, translation in client units).
  Vec3 scene_position(const std::array<double, 16>& pose) const;
  // A scene point (m) in the client's frame and units (for the surface sent back).
  Vec3 client_position(const Vec3& scene) const;
  // A scene vector (force, torque) in the client's axes; its unit is kept (N, N m).
  Vec3 client_direction(const Vec3& scene) const;
  // A scene 3x3 map between vectors (the contact stiffness dF/dc) in the
  // client's axes, R^T K R; its unit is kept (N/m).
  Eigen::Matrix3d client_matrix(const Eigen::Matrix3d& scene) const;
};

// "mm" or "m" (Error(Usage) naming the option otherwise).
double client_unit_metres(const std::string& unit);

// Reads a JSON file holding a rigid 4x4 matrix as four rows of four numbers
// ({"matrix": [[...], ...]} or the bare array). Error(Input) naming the file
// when it is not one: unreadable, not JSON, not 4x4, not finite, last row not
// [0, 0, 0, 1], or an upper 3x3 that is not a rotation (within 1e-6).
Matrix4 read_client_transform(const std::filesystem::path& file);
// The same from the file's text; errors name `source`.
Matrix4 parse_client_transform(std::string_view text, const std::string& source);

// A box around the scene: poses whose centre falls outside it are refused
// (a client sending metres to a server expecting millimetres lands 1000x
// too far). The model's bounding box grown on every side by its largest extent.
struct SceneBox {
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
  bool contains(const Vec3& p) const;
};
SceneBox scene_box(const std::vector<Vec3>& points);

}  // namespace organsim
