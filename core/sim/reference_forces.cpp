#include "core/sim/reference_forces.h"

#include "core/model/nodal_volume.h"
#include "core/model/shear_element.h"
#include "core/physics/force_law.h"

namespace organsim {

void reference_internal_forces(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                               std::vector<Vec3>& force, double t) {
  force.assign(model.npoint(), Vec3::Zero());
  // Springs and their dampers; sutures pull only (core/physics/force_law.h).
  for (int32_t s = 0; s < model.nspring(); ++s) {
    const auto [a, b] = model.spring_ends[s];
    const Vec3 l = x[b] - x[a];
    const double length = l.norm();
    if (length <= 0) continue;  // coincident ends: no defined direction, no force
    const Vec3 u = l / length;
    const double rest = model.spring_rest_at(s, t);
    double tension = force_law::spring_tension(model.spring_k[s], model.spring_d[s], length, rest, (v[b] - v[a]).dot(u));
    if (s >= model.first_suture()) tension = force_law::suture_tension(tension, length, rest);
    force[a] += tension * u;
    force[b] -= tension * u;
  }
  // Volume: f_i = -p dV/dx_i with the tet's pressure p = k_v (V - V_r), or
  // with the nodal term the mean of its corners' nodal pressures.
  if (model.has_volume()) {
    // Kept per thread between calls, so that a step allocates nothing once sized.
    thread_local std::vector<double> q;
    if (model.has_nodal_volume()) nodal_pressures(model, x, q);
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const Tet& tet = model.tet_points[t];
      const Vec3 e1 = x[tet[1]] - x[tet[0]], e2 = x[tet[2]] - x[tet[0]], e3 = x[tet[3]] - x[tet[0]];
      const double p = model.has_nodal_volume()
                           ? force_law::tet_pressure_from_nodal(q[tet[0]], q[tet[1]], q[tet[2]], q[tet[3]])
                           : force_law::volume_pressure(model.tet_k[t], force_law::tet_volume6(e1, e2, e3) / 6,
                                                        model.tet_rest_volume[t]);
      Vec3 g1, g2, g3;  // 6 dV/dx_k
      force_law::tet_volume_gradients6(e1, e2, e3, g1, g2, g3);
      const double scale = -p / 6;
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

Reaction reference_push_forces(const std::vector<Vec3>& x, const ToolPlacement& tool, double stiffness,
                               std::vector<Vec3>& force, const std::vector<double>& scale) {
  Reaction reaction;
  for (size_t i = 0; i < x.size(); ++i) {
    const Vec3 offset = x[i] - force_law::segment_closest_point(x[i], tool.a, tool.b);
    Vec3 f;
    if (!force_law::push_penalty(offset, tool.radius, stiffness * (scale.empty() ? 1.0 : scale[i]), f)) continue;
    force[i] += f;
    reaction.force -= f;
    reaction.torque += (x[i] - tool.origin).cross(-f);
    ++reaction.contacts;
  }
  return reaction;
}

Reaction reference_push_forces(const std::vector<Vec3>& x, const Vec3& center, double radius, double stiffness,
                               std::vector<Vec3>& force, const std::vector<double>& scale) {
  return reference_push_forces(x, ToolPlacement{center, center, center, radius}, stiffness, force, scale);
}

Reaction reference_surface_forces(const Model& model, const std::vector<Vec3>& x, const ToolPlacement& tool,
                                  double stiffness, std::vector<Vec3>& force, const ContactLayer* layer) {
  struct Touch {
    const Tri* t;
    Vec3 f;
    double w[3];
    int jaw;
  };
  std::vector<Touch> touches;
  force_law::HertzLayer hertz;
  const Vec3 seg_a[2] = {tool.a, tool.a2}, seg_b[2] = {tool.b, tool.b2};
  for (const Tri& t : model.surface) {
    double share[3];
    for (int i = 0; i < 3; ++i) share[i] = model.tool_scale(t[i]) / model.surface_count(t[i]);
    for (int jaw = 0; jaw < tool.jaws; ++jaw) {
      Touch touch{&t, Vec3::Zero(), {0, 0, 0}, jaw};
      if (!force_law::capsule_triangle_penalty(seg_a[jaw], seg_b[jaw], tool.radius, x[t[0]], x[t[1]], x[t[2]],
                                               stiffness, share, touch.f, touch.w))
        continue;
      if (layer) {
        const TriangleLayer tl = triangle_layer(*layer, t);
        const Vec3 q = touch.w[0] * x[t[0]] + touch.w[1] * x[t[1]] + touch.w[2] * x[t[2]];
        hertz.add(touch.f.data(), stiffness * force_law::triangle_penalty_scale(share), tl.punch_radius, tl.e_star,
                  force_law::segment_axial_position(q, seg_a[jaw], seg_b[jaw]));
      }
      touches.push_back(touch);
    }
  }
  if (layer) hertz.solve(tool.radius);
  Reaction reaction;
  std::vector<Vec3> received(x.size(), Vec3::Zero());
  std::vector<uint8_t> touched(x.size(), 0);
  const Vec3 axis = tool.rotation * kJawAxis, closing[2] = {-axis, axis};
  for (size_t k = 0; k < touches.size(); ++k) {
    const Touch& touch = touches[k];
    const Tri& t = *touch.t;
    const Vec3 f = layer ? Vec3(hertz.factor(k) * touch.f) : touch.f;
    const Vec3 q = touch.w[0] * x[t[0]] + touch.w[1] * x[t[1]] + touch.w[2] * x[t[2]];
    for (int i = 0; i < 3; ++i) {
      received[t[i]] += touch.w[i] * f;
      touched[t[i]] = 1;
    }
    reaction.force -= f;
    reaction.torque += (q - tool.origin).cross(-f);
    if (tool.jaws == 2) reaction.grip += f.dot(closing[touch.jaw]);
  }
  for (size_t p = 0; p < x.size(); ++p) {
    force[p] += received[p];
    reaction.contacts += touched[p];
  }
  return reaction;
}

Reaction reference_surface_forces(const Model& model, const std::vector<Vec3>& x, const Vec3& center,
                                  double radius, double stiffness, std::vector<Vec3>& force, const ContactLayer* layer) {
  return reference_surface_forces(model, x, ToolPlacement{center, center, center, radius}, stiffness, force, layer);
}

Reaction reference_pull_forces(const std::vector<Vec3>& x, const Attachment& attachment, const Vec3& center,
                               double stiffness, std::vector<Vec3>& force, const std::vector<double>& scale) {
  Reaction reaction;
  for (size_t k = 0; k < attachment.points.size(); ++k) {
    const int32_t i = attachment.points[k];
    const Vec3 f = force_law::pull_attachment(Vec3(center + attachment.offsets[k]), x[i],
                                              stiffness * (scale.empty() ? 1.0 : scale[i]));
    force[i] += f;
    reaction.force -= f;
    reaction.torque += (x[i] - center).cross(-f);
    ++reaction.contacts;
  }
  return reaction;
}

}  // namespace organsim
