#include "core/model/contact_layer.h"

#include <cmath>

#include "core/model/stiffness.h"

namespace organsim {

ContactLayer contact_layer(const Model& model) {
  ContactLayer layer;
  std::vector<double> ring(model.npoint(), 0.0);
  for (const Tri& t : model.surface) {
    const Vec3 &x0 = model.rest_position[t[0]], &x1 = model.rest_position[t[1]], &x2 = model.rest_position[t[2]];
    const double area = 0.5 * (x1 - x0).cross(x2 - x0).norm();
    for (int i = 0; i < 3; ++i) ring[t[i]] += area;
  }
  layer.punch_radius.resize(model.npoint());
  for (int32_t p = 0; p < model.npoint(); ++p) layer.punch_radius[p] = std::sqrt(ring[p] / M_PI);
  std::vector<double> sum(model.npoint(), 0.0);
  std::vector<int32_t> count(model.npoint(), 0);
  for (int32_t t = 0; t < model.ntet(); ++t) {
    const EffectiveElasticity e = effective_elasticity(model.material_of_tet(t));
    const double e_star = e.young_modulus / (1 - e.poisson_ratio * e.poisson_ratio);
    for (int32_t p : model.tet_points[t]) sum[p] += e_star, ++count[p];
  }
  layer.e_star.resize(model.npoint());
  for (int32_t p = 0; p < model.npoint(); ++p) layer.e_star[p] = count[p] > 0 ? sum[p] / count[p] : 0.0;
  return layer;
}

TriangleLayer triangle_layer(const ContactLayer& layer, const Tri& t) {
  TriangleLayer r;
  for (int i = 0; i < 3; ++i) {
    r.punch_radius += layer.punch_radius[t[i]] / 3;
    r.e_star += layer.e_star[t[i]] / 3;
  }
  return r;
}

}  // namespace organsim
