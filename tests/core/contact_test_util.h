#pragma once
// What the tool-contact tests share (surface_contact_test.cpp for the
// sphere, capsule_contact_test.cpp for the capsule): a jittered box with a
// fixed bottom, the contact forces of one evaluation and their largest
// per-point change between two.
#include <algorithm>
#include <vector>

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

inline double largest_change(const Contact& a, const Contact& b) {
  double worst = 0;
  for (size_t i = 0; i < a.force.size(); ++i) worst = std::max(worst, (a.force[i] - b.force[i]).norm());
  return worst;
}

}  // namespace organsim::testing
