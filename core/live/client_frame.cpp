#include "core/live/client_frame.h"

#include <nlohmann/json.hpp>

#include <cmath>

#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

Vec3 ClientFrame::scene_position(const std::array<double, 16>& pose) const {
  const Eigen::Vector4d origin(pose[3], pose[7], pose[11], 1.0);
  const Eigen::Vector4d scene = to_scene * origin;
  return metres_per_unit * scene.head<3>();
}

Vec3 ClientFrame::client_position(const Vec3& scene) const {
  const Vec3 p = scene / metres_per_unit;
  return to_scene.topLeftCorner<3, 3>().transpose() * (p - to_scene.topRightCorner<3, 1>());
}

Vec3 ClientFrame::client_direction(const Vec3& scene) const {
  return to_scene.topLeftCorner<3, 3>().transpose() * scene;
}

Eigen::Matrix3d ClientFrame::client_matrix(const Eigen::Matrix3d& scene) const {
  const Eigen::Matrix3d r = to_scene.topLeftCorner<3, 3>();
  return r.transpose() * scene * r;
}

double client_unit_metres(const std::string& unit) {
  if (unit == "mm") return 1e-3;
  if (unit == "m") return 1.0;
  throw Error(ErrorKind::Usage, "--client-units: expected mm or m (got \"" + unit + "\")");
}

Matrix4 read_client_transform(const std::filesystem::path& file) {
  return parse_client_transform(read_text_file(file), file.string());
}

Matrix4 parse_client_transform(std::string_view text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw input_error(source, std::string("not JSON (") + e.what() + ")");
  }
  if (j.is_object() && j.contains("matrix")) j = j["matrix"];
  const char* expected = "expected a 4x4 matrix: four rows of four numbers, or {\"matrix\": [[...], ...]}";
  if (!j.is_array() || j.size() != 4) throw input_error(source, expected);
  Matrix4 m;
  for (int r = 0; r < 4; ++r) {
    if (!j[r].is_array() || j[r].size() != 4) throw input_error(source, expected);
    for (int c = 0; c < 4; ++c) {
      if (!j[r][c].is_number()) throw input_error(source, expected);
      m(r, c) = j[r][c].get<double>();
      if (!std::isfinite(m(r, c))) throw input_error(source, "matrix entries must be finite");
    }
  }
  if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) throw input_error(source, "the last row must be [0, 0, 0, 1]");
  const Eigen::Matrix3d rot = m.topLeftCorner<3, 3>();
  const double off = (rot.transpose() * rot - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  // Asked so that NaN (entries whose products overflow) is refused too.
  if (!(off <= 1e-6) || !(rot.determinant() > 0))
    throw input_error(source,
                      "the upper 3x3 must be a rotation (orthonormal, determinant +1): the client's "
                      "frame is registered rigidly; units are --client-units");
  return m;
}

bool SceneBox::contains(const Vec3& p) const {
  return p.allFinite() && (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

SceneBox scene_box(const std::vector<Vec3>& points) {
  SceneBox b;
  if (points.empty()) return b;
  b.lo = b.hi = points.front();
  for (const Vec3& p : points) {
    b.lo = b.lo.cwiseMin(p);
    b.hi = b.hi.cwiseMax(p);
  }
  const double grow = (b.hi - b.lo).maxCoeff();
  b.lo.array() -= grow;
  b.hi.array() += grow;
  return b;
}

}  // namespace organsim
