#include "core/scenario/tool_spec.h"

#include <algorithm>

namespace organsim {

Vec3 ToolSpec::position_at(double t) const {
  if (keyframes.empty()) return Vec3::Zero();
  if (t <= keyframes.front().t) return keyframes.front().position;
  if (t >= keyframes.back().t) return keyframes.back().position;
  // The first keyframe at or after t (a recorded live session has one per
  // tick, so a scan per tick would make its replay quadratic).
  const auto b = std::lower_bound(keyframes.begin(), keyframes.end(), t,
                                  [](const Keyframe& k, double time) { return k.t < time; });
  // Exactly the keyframe's position at its time: a + 1 * (b - a) can differ
  // from b in the last bit, and a replayed live session must put the tool
  // exactly where the client did.
  if (b->t == t) return b->position;
  const Keyframe& a = *(b - 1);
  const double s = (t - a.t) / (b->t - a.t);
  return a.position + s * (b->position - a.position);
}

}  // namespace organsim
