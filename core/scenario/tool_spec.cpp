#include "core/scenario/tool_spec.h"

#include <algorithm>

namespace organsim {

BackendTool ToolSpec::backend_tool() const {
  BackendTool t;
  t.present = true;
  t.mode = mode;
  t.radius = radius;
  t.contact_stiffness = contact_stiffness;
  t.contact = contact;
  t.shape = shape;
  t.end_a = end_a;
  t.end_b = end_b;
  t.friction = friction;
  t.hertz_layer = hertz_layer;
  return t;
}

double ToolSpec::extent() const {
  if (shape == ToolShape::Sphere) return 0.0;
  double widest = 0;
  if (shape == ToolShape::Grasper)
    for (const Keyframe& k : keyframes) widest = std::max(widest, k.gap);
  return std::max(end_a.norm(), end_b.norm()) + widest / 2;
}

namespace {
// The keyframe at or before t (`a`) and, strictly between two keyframes,
// the next one (`b`, else null) and how far t lies from a to b (s in (0, 1)).
// Exactly a keyframe at its time: a + 1 * (b - a) can differ from b in the
// last bit, and a replayed live session must put the tool exactly where the
// client did.
struct Bracket {
  const Keyframe* a = nullptr;
  const Keyframe* b = nullptr;
  double s = 0;
};
Bracket bracket(const std::vector<Keyframe>& keyframes, double t) {
  if (t <= keyframes.front().t) return {&keyframes.front()};
  if (t >= keyframes.back().t) return {&keyframes.back()};
  // The first keyframe at or after t (a recorded live session has one per
  // tick, so a scan per tick would make its replay quadratic).
  const auto b = std::lower_bound(keyframes.begin(), keyframes.end(), t,
                                  [](const Keyframe& k, double time) { return k.t < time; });
  if (b->t == t) return {&*b};
  const Keyframe& a = *(b - 1);
  return {&a, &*b, (t - a.t) / (b->t - a.t)};
}
}  // namespace

Vec3 ToolSpec::position_at(double t) const {
  if (keyframes.empty()) return Vec3::Zero();
  const Bracket k = bracket(keyframes, t);
  return k.b ? Vec3(k.a->position + k.s * (k.b->position - k.a->position)) : k.a->position;
}

double ToolSpec::gap_at(double t) const {
  if (keyframes.empty()) return 0.0;
  const Bracket k = bracket(keyframes, t);
  return k.b ? k.a->gap + k.s * (k.b->gap - k.a->gap) : k.a->gap;
}

Quat ToolSpec::orientation_at(double t) const {
  if (keyframes.empty()) return Quat::Identity();
  const Bracket k = bracket(keyframes, t);
  // Eigen's slerp takes the shorter of the two arcs (q and -q are one rotation).
  return k.b ? k.a->orientation.slerp(k.s, k.b->orientation) : k.a->orientation;
}

}  // namespace organsim
