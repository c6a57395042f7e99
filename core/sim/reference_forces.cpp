#include "core/sim/reference_forces.h"

#include "core/model/nodal_volume.h"
#include "core/model/shear_element.h"

namespace organsim {

void reference_internal_forces(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                               std::vector<Vec3>& force, double t) {
  force.assign(model.npoint(), Vec3::Zero());
  // Spring + damper: f_a = [k (L - r) + d ((v_b - v_a) . u)] u, f_b = -f_a.
  for (int32_t s = 0; s < model.nspring(); ++s) {
    const auto [a, b] = model.spring_ends[s];
    const Vec3 l = x[b] - x[a];
    const double length = l.norm();
    if (length <= 0) continue;  // coincident ends: no defined direction, no force
    const Vec3 u = l / length;
    const double rest = model.spring_rest_at(s, t);
    const double pull = model.spring_k[s] * (length - rest) + model.spring_d[s] * (v[b] - v[a]).dot(u);
    if (s >= model.first_suture() && !(length > rest && pull > 0)) continue;  // a slack suture
    const Vec3 f = pull * u;
    force[a] += f;
    force[b] -= f;
  }
  // Volume, per tet: f_i = k_v (V_r - V) dV/dx_i, gradient of E = k_v/2 (V - V_r)^2.
  // Nodal: f_i = -p_t dV/dx_i with p_t the mean of the tet's nodal pressures.
  if (model.has_volume()) {
    std::vector<double> q;
    if (model.has_nodal_volume()) nodal_pressures(model, x, q);
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const Tet& tet = model.tet_points[t];
      const Vec3 &p0 = x[tet[0]], &p1 = x[tet[1]], &p2 = x[tet[2]], &p3 = x[tet[3]];
      const double scale = model.has_nodal_volume()
                               ? -(q[tet[0]] + q[tet[1]] + q[tet[2]] + q[tet[3]]) / 4
                               : model.tet_k[t] * (model.tet_rest_volume[t] - signed_volume(p0, p1, p2, p3));
      // dV/dp1 = (p2-p0)x(p3-p0)/6, dV/dp2 = (p3-p0)x(p1-p0)/6, dV/dp3 = (p1-p0)x(p2-p0)/6, dV/dp0 = -sum.
      const Vec3 g1 = (p2 - p0).cross(p3 - p0) / 6.0;
      const Vec3 g2 = (p3 - p0).cross(p1 - p0) / 6.0;
      const Vec3 g3 = (p1 - p0).cross(p2 - p0) / 6.0;
      force[tet[0]] -= scale * (g1 + g2 + g3);
      force[tet[1]] += scale * g1;
      force[tet[2]] += scale * g2;
      force[tet[3]] += scale * g3;
    }
  }
  // Shear element (nu < 1/4) and its damper (core/model/shear_element.h).
  add_shear_element_forces(model, x, force);
  add_shear_element_damping_forces(model, x, v, force);
  if (model.has_gravity())
    for (int32_t i = 0; i < model.npoint(); ++i) force[i] += model.mass[i] * model.gravity;
}

Reaction reference_push_forces(const std::vector<Vec3>& x, const Vec3& center, double radius, double stiffness,
                               std::vector<Vec3>& force, const std::vector<double>& scale) {
  Reaction reaction;
  for (size_t i = 0; i < x.size(); ++i) {
    const Vec3 d = x[i] - center;
    const double dist = d.norm();
    if (dist >= radius) continue;
    // At the exact centre the direction is undefined; push along +z.
    const Vec3 n = dist > 0 ? Vec3(d / dist) : Vec3(0, 0, 1);
    const Vec3 f = stiffness * (scale.empty() ? 1.0 : scale[i]) * (radius - dist) * n;
    force[i] += f;
    reaction.force -= f;
    reaction.torque += d.cross(-f);
    ++reaction.contacts;
  }
  return reaction;
}

Reaction reference_pull_forces(const std::vector<Vec3>& x, const Attachment& attachment, const Vec3& center,
                               double stiffness, std::vector<Vec3>& force, const std::vector<double>& scale) {
  Reaction reaction;
  for (size_t k = 0; k < attachment.points.size(); ++k) {
    const int32_t i = attachment.points[k];
    const Vec3 f = stiffness * (scale.empty() ? 1.0 : scale[i]) * (center + attachment.offsets[k] - x[i]);
    force[i] += f;
    reaction.force -= f;
    reaction.torque += (x[i] - center).cross(-f);
    ++reaction.contacts;
  }
  return reaction;
}

}  // namespace organsim
