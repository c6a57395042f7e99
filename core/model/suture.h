#pragma once
// A suture: a thread joining two points, added to a running model by a
// scenario `suture` event (core/topology/suture_select.h). In the Model it is
// a spring like the tissue's, with two differences every backend honours:
// it pulls and never pushes (no force while its length is at or below its
// rest length, and the damper never turns the pull into a push), and its rest
// length follows an immutable tightening schedule, so the Model stays the
// same while the suture tightens. SI units.
#include <algorithm>

#include "core/mesh/tet_mesh.h"

namespace organsim {

struct Suture {
  Edge ends{};            // internal ids, ends[0] < ends[1]
  double k = 0;           // stiffness, N/m
  double tied_at = 0;     // time the suture was tied, s
  double length = 0;      // rest length when tied, m
  double rate = 0;        // tightening speed, m/s (>= 0)
  double min_length = 0;  // tightening stops here, m (>= 0)

  // max(min_length, length - rate (t - tied_at)); `length` before it is tied.
  double rest_at(double t) const {
    const double shortened = length - rate * std::max(0.0, t - tied_at);
    return std::max(min_length, shortened);
  }
};

}  // namespace organsim
