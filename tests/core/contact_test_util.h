#pragma once
// What the tool-contact tests share (surface_contact_test.cpp for the
// sphere, capsule_contact_test.cpp for the capsule): a jittered box with a
// fixed bottom, the contact forces of one evaluation and their largest
// per-point change between two.
#include <algorithm>
#include <vector>

#include "core/sim/backend.h"
#include "core/sim/reference_forces.h"
#include "tests/core/test_models.h"

namespace organsim::testing {

constexpr double kContactBox = 0.04;  // m, box edge
constexpr double kContactK = 500;     // N/m, contact stiffness

// cells^3 cubes of kContactBox, E = 4 kPa, held at the bottom.
inline Model contact_box(int cells) {
  Material material;
  material.density = 1000;
  material.young_modulus = 4000;
  material.spring_damping_time = 0.01;
  material.viscous_damping = 5;
  return build_model(jittered_box(cells, kContactBox, 0.2, 5), material, fixed_bottom_options());
}

struct Contact {
  Reaction reaction;
  std::vector<Vec3> force;  // per point
};

// One step of dt with the tool held still at `origin`, turned by `turn`.
inline TickRequest one_step_at(double dt, const Vec3& origin, const Quat& turn = Quat::Identity()) {
  TickRequest r;
  r.dt = dt;
  r.substeps = 1;
  r.tool_active = true;
  r.tool_from = r.tool_to = origin;
  r.turn_from = r.turn_to = turn;
  return r;
}

// The force one step of dt from rest applied to each free point, read from
// its displacement (f = m u / dt^2: no velocity, no internal force at
// rest), against `want` per point: their sum, the largest difference and
// the largest wanted force.
struct Applied {
  Vec3 received = Vec3::Zero();
  double worst = 0, peak = 0;
};
inline Applied applied_in_one_step(const Model& m, const Backend& backend, double dt, const std::vector<Vec3>& want) {
  std::vector<Vec3> x;
  backend.positions(x);
  Applied out;
  for (int32_t i = 0; i < m.npoint(); ++i) {
    if (m.fixed[i]) continue;
    const Vec3 f = m.mass[i] * (x[i] - m.rest_position[i]) / (dt * dt);
    out.received += f;
    out.worst = std::max(out.worst, (f - want[i]).norm());
    out.peak = std::max(out.peak, want[i].norm());
  }
  return out;
}

inline double largest_change(const Contact& a, const Contact& b) {
  double worst = 0;
  for (size_t i = 0; i < a.force.size(); ++i) worst = std::max(worst, (a.force[i] - b.force[i]).norm());
  return worst;
}

}  // namespace organsim::testing
