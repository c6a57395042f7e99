#pragma once
// What the sub-cell Hertz layer (force_law::HertzLayer) needs of a
// Model, per point, computed once per Model version (cuts change the
// surface): how wide a contact the cells resolve there and how stiff the
// material is.
#include <vector>

#include "core/model/model.h"

namespace organsim {

struct ContactLayer {
  // sqrt(A / pi), A the rest area of the point's boundary triangles (its
  // vertex ring), m; 0 off the surface. A linear triangle mesh pressed at a
  // point moves like a flat punch of about this radius.
  std::vector<double> punch_radius;
  // E* = E / (1 - nu^2) of the point's tets' materials (their mean), Pa.
  std::vector<double> e_star;
};

ContactLayer contact_layer(const Model& model);

// A triangle's values: the mean of its corners' (a_h before the layer's
// factor, and E*).
struct TriangleLayer {
  double punch_radius = 0, e_star = 0;
};
TriangleLayer triangle_layer(const ContactLayer& layer, const Tri& t);

}  // namespace organsim
