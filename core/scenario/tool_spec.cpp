#include "core/scenario/tool_spec.h"

namespace organsim {

Vec3 ToolSpec::position_at(double t) const {
  if (keyframes.empty()) return Vec3::Zero();
  if (t <= keyframes.front().t) return keyframes.front().position;
  if (t >= keyframes.back().t) return keyframes.back().position;
  for (size_t i = 1; i < keyframes.size(); ++i) {
    const Keyframe& a = keyframes[i - 1];
    const Keyframe& b = keyframes[i];
    if (t <= b.t) {
      const double span = b.t - a.t;
      const double s = span > 0 ? (t - a.t) / span : 1.0;
      return a.position + s * (b.position - a.position);
    }
  }
  return keyframes.back().position;
}

}  // namespace organsim
