#include "core/sim/scatter_step.h"

#include <algorithm>

#include "core/model/shear_element.h"
#include "core/physics/force_law.h"

namespace organsim {

template <class Real>
ScatterStep<Real>::ScatterStep(const Model& model)
    : model_(model), u_(model.npoint(), V3::Zero()), d_(model.npoint(), V3::Zero()), force_(model.npoint()),
      nodal_(model.has_nodal_volume() ? model.npoint() : 0) {
  rest_.reserve(model.npoint());
  for (const Vec3& x : model.rest_position) rest_.push_back(x.cast<Real>());
}

template <class Real>
void ScatterStep<Real>::step(double dt_seconds) {
  const Model& m = model_;
  const Real dt = static_cast<Real>(dt_seconds), inv_dt = 1 / dt;
  const Real drag = static_cast<Real>(1 - m.viscous_damping * dt_seconds);
  const V3 gravity = m.gravity.cast<Real>();
  for (int32_t i = 0; i < m.npoint(); ++i) force_[i] = static_cast<Real>(m.mass[i]) * gravity;
  auto x = [&](int32_t i) -> V3 { return rest_[i] + u_[i]; };
  // Springs and their dampers; sutures pull only (core/physics/force_law.h).
  const double t = time_;
  for (int32_t s = 0; s < m.nspring(); ++s) {
    const auto [a, b] = m.spring_ends[s];
    const V3 l = x(b) - x(a);
    const Real length = l.norm();
    if (length <= 0) continue;
    const V3 dir = l / length;
    const Real rest = static_cast<Real>(m.spring_rest_at(s, t));
    Real tension = force_law::spring_tension(static_cast<Real>(m.spring_k[s]), static_cast<Real>(m.spring_d[s]),
                                             length, rest, (d_[b] - d_[a]).dot(dir) * inv_dt);
    if (s >= m.first_suture()) tension = force_law::suture_tension(tension, length, rest);
    force_[a] += tension * dir;
    force_[b] -= tension * dir;
  }
  auto tet_volume = [&](const Tet& tet) {
    const V3 p0 = x(tet[0]);
    return force_law::tet_volume6(V3(x(tet[1]) - p0), V3(x(tet[2]) - p0), V3(x(tet[3]) - p0)) / 6;
  };
  // Nodal volume term, first pass: pressures q_a = k_a (V_a - V_a^r), V_a = sum of V_t / 4.
  if (m.has_nodal_volume()) {
    std::fill(nodal_.begin(), nodal_.end(), Real(0));
    for (const Tet& tet : m.tet_points) {
      const Real quarter = tet_volume(tet) / 4;
      for (int32_t p : tet) nodal_[p] += quarter;
    }
    for (int32_t a = 0; a < m.npoint(); ++a)
      nodal_[a] = force_law::volume_pressure(static_cast<Real>(m.point_volume_k[a]), nodal_[a],
                                             static_cast<Real>(m.point_rest_volume[a]));
  }
  // Volume: f_i = -p dV/dx_i with p = k_v (V - V_r) per tet, or the mean
  // nodal pressure of the tet's corners.
  if (m.has_volume()) {
    for (int32_t t = 0; t < m.ntet(); ++t) {
      const Tet& tet = m.tet_points[t];
      const V3 p0 = x(tet[0]), e1 = x(tet[1]) - p0, e2 = x(tet[2]) - p0, e3 = x(tet[3]) - p0;
      const Real p = m.has_nodal_volume()
                         ? force_law::tet_pressure_from_nodal(nodal_[tet[0]], nodal_[tet[1]], nodal_[tet[2]],
                                                              nodal_[tet[3]])
                         : force_law::volume_pressure(static_cast<Real>(m.tet_k[t]), tet_volume(tet),
                                                      static_cast<Real>(m.tet_rest_volume[t]));
      V3 g1, g2, g3;  // 6 dV/dx_k
      force_law::tet_volume_gradients6(e1, e2, e3, g1, g2, g3);
      const Real scale = -p / 6;
      force_[tet[0]] -= scale * (g1 + g2 + g3);
      force_[tet[1]] += scale * g1;
      force_[tet[2]] += scale * g2;
      force_[tet[3]] += scale * g3;
    }
  }
  // Shear element: f_i = -k_t (F + phi'(J) cof F) g_i with F = I + sum_i u_i g_i^T
  // (from the displacements, so the rest state is exactly force-free), and
  // its damper -(2 tau k_t / J_d) sym(Fdot cof^T) cof g_i, dt Fdot = sum_i d_i g_i^T.
  // Smoothed: (1 - s) of the per-tet stress, s of the mean of the corners'
  // P(Fbar_a), Fbar_a = I + sum over the tets of a of k_t (F_t - I) / K_a.
  const Real tau = static_cast<Real>(m.shear_damping_time);
  const Real s = static_cast<Real>(m.shear_smoothed_share);
  auto gradient = [&](int32_t t, const std::vector<V3>& w) {
    const Tet& tet = m.tet_points[t];
    M3 h = M3::Zero();
    for (int i = 1; i < 4; ++i) h += (w[tet[i]] - w[tet[0]]) * m.tet_shape_gradient[t][i].cast<Real>().transpose();
    return h;
  };
  if (m.has_smoothed_shear()) {
    stress_.assign(m.npoint(), M3::Zero());
    for (int32_t t = 0; t < m.ntet(); ++t) {
      const M3 h = Real(m.tet_shear_k[t]) * gradient(t, u_);
      for (int32_t a : m.tet_points[t]) stress_[a] += h;
    }
    for (int32_t a = 0; a < m.npoint(); ++a) {
      const Real k = static_cast<Real>(m.point_shear_k[a]);
      stress_[a] = force_law::shear_stress<M3>(M3::Identity() + (k > 0 ? M3(stress_[a] / k) : M3::Zero()));
    }
  }
  for (int32_t t = 0; t < static_cast<int32_t>(m.tet_shear_k.size()); ++t) {
    const Tet& tet = m.tet_points[t];
    const M3 F = M3::Identity() + gradient(t, u_), Fdot = gradient(t, d_) * inv_dt;
    const M3 cof = force_law::shear_cofactor(F);
    const Real J = F.col(0).dot(cof.col(0));
    M3 stress = (1 - s) * (F + force_law::shear_barrier_slope(J) * cof) + force_law::shear_damping_stress(Fdot, cof, J, tau);
    if (m.has_smoothed_shear())
      stress += (s / 4) * (stress_[tet[0]] + stress_[tet[1]] + stress_[tet[2]] + stress_[tet[3]]);
    const M3 P = Real(m.tet_shear_k[t]) * stress;
    for (int i = 0; i < 4; ++i) force_[tet[i]] -= P * m.tet_shape_gradient[t][i].cast<Real>();
  }
  // Position Verlet with drag: d' = (1 - alpha dt) d + dt^2 F/m, u' = u + d'.
  for (int32_t i = 0; i < m.npoint(); ++i) {
    if (m.fixed[i]) continue;
    d_[i] = drag * d_[i] + (dt * dt * static_cast<Real>(m.inv_mass[i])) * force_[i];
    u_[i] += d_[i];
  }
  time_ += dt_seconds;
}

template <class Real>
void ScatterStep<Real>::positions(std::vector<Vec3>& out) const {
  out.resize(u_.size());
  for (size_t i = 0; i < u_.size(); ++i) out[i] = model_.rest_position[i] + u_[i].template cast<double>();
}

template class ScatterStep<float>;
template class ScatterStep<double>;

}  // namespace organsim
