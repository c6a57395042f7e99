#include "core/mesh/units.h"

#include <sstream>

namespace organsim {

std::optional<double> metres_per_unit(std::string_view unit) {
  if (unit == "mm") return 1e-3;
  if (unit == "cm") return 1e-2;
  if (unit == "m") return 1.0;
  return std::nullopt;
}

void scale_points(std::vector<Vec3>& points, double scale) {
  for (Vec3& p : points) p *= scale;
}

std::string describe_extent(const std::vector<Vec3>& points) {
  if (points.empty()) return "empty";
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 size = hi - lo;
  std::ostringstream s;
  s.precision(4);
  s << size.x() << " x " << size.y() << " x " << size.z() << " m";
  return s.str();
}

}  // namespace organsim
