#pragma once
// Small vector aliases shared by every organsim module (SI units throughout).
#include <Eigen/Core>
#include <Eigen/Geometry>  // cross()
#include <array>
#include <cstdint>

namespace organsim {

using Vec3 = Eigen::Vector3d;
using Vec3f = Eigen::Vector3f;
// A rotation as a unit quaternion (w, x, y, z).
using Quat = Eigen::Quaterniond;
using Tet = std::array<int32_t, 4>;
using Tri = std::array<int32_t, 3>;
using Edge = std::array<int32_t, 2>;

}  // namespace organsim
