#include "core/sim/implicit_system.h"

#include "core/model/rest_stiffness.h"
#include "core/physics/force_law.h"

namespace organsim {

namespace {

Eigen::SparseMatrix<double, Eigen::RowMajor> row_major(const Model& model, const Triplets& t) {
  return Eigen::SparseMatrix<double, Eigen::RowMajor>(assemble(model, t));
}

Eigen::Map<const Eigen::Vector3d> at(const Eigen::VectorXd& v, int32_t p) { return Eigen::Map<const Eigen::Vector3d>(v.data() + 3 * p); }
Eigen::Map<Eigen::Vector3d> at(Eigen::VectorXd& v, int32_t p) { return Eigen::Map<Eigen::Vector3d>(v.data() + 3 * p); }

}  // namespace

ImplicitSystem::ImplicitSystem(const Model& model) : model_(model) {
  if (model.has_shear_element()) {
    shear_k_ = row_major(model, rest_stiffness(model, RestTerms::ShearElement));
    shear_d_ = row_major(model, rest_damping(model, RestTerms::ShearElement));
  }
  if (model.has_nodal_volume()) {
    tets_of_point_.assign(model.npoint(), {});
    for (int32_t t = 0; t < model.ntet(); ++t)
      for (int32_t p : model.tet_points[t]) tets_of_point_[p].push_back(t);
  }
}

void ImplicitSystem::linearise(const std::vector<Vec3>& x, const std::vector<Vec3>& v, double t,
                               const std::vector<ContactBlock>& contact) {
  const Model& m = model_;
  springs_.assign(m.nspring(), {});
  for (int32_t s = 0; s < m.nspring(); ++s) {
    const auto [a, b] = m.spring_ends[s];
    const Vec3 l = x[b] - x[a];
    const double length = l.norm();
    if (!(length > 0)) continue;  // coincident ends: no direction, no force, no stiffness
    const Vec3 u = l / length;
    const double rest = m.spring_rest_at(s, t);
    double tension = force_law::spring_tension(m.spring_k[s], m.spring_d[s], length, rest, (v[b] - v[a]).dot(u));
    // A slack suture (or one its damper would turn into a push) exerts nothing, so it stiffens nothing.
    if (s >= m.first_suture() && force_law::suture_tension(tension, length, rest) == 0) continue;
    const double transverse = force_law::spring_transverse_stiffness(tension, length);
    springs_[s] = {u, m.spring_k[s] - transverse, transverse, m.spring_d[s]};
  }
  volume_gradient_.clear();
  if (m.has_volume()) {
    volume_gradient_.resize(m.ntet());
    for (int32_t e = 0; e < m.ntet(); ++e) {
      const Tet& tet = m.tet_points[e];
      const Vec3 e1 = x[tet[1]] - x[tet[0]], e2 = x[tet[2]] - x[tet[0]], e3 = x[tet[3]] - x[tet[0]];
      Vec3 g1, g2, g3;  // 6 dV/dx_k
      force_law::tet_volume_gradients6(e1, e2, e3, g1, g2, g3);
      volume_gradient_[e] = {-(g1 + g2 + g3) / 6, g1 / 6, g2 / 6, g3 / 6};
    }
  }
  contact_ = contact;
}

void ImplicitSystem::apply(double m_coef, double alpha, double beta, const Eigen::VectorXd& p,
                           Eigen::VectorXd& out) const {
  const Model& m = model_;
  const int32_t n = m.npoint();
  out.resize(3 * n);
  for (int32_t i = 0; i < n; ++i) at(out, i) = (m_coef + alpha * m.viscous_damping) * m.mass[i] * at(p, i);
  for (int32_t s = 0; s < m.nspring(); ++s) {
    const SpringTangent& g = springs_[s];
    const auto [a, b] = m.spring_ends[s];
    const Vec3 delta = at(p, a) - at(p, b);
    const Vec3 y = (alpha * g.d + beta * g.axial) * g.u.dot(delta) * g.u + beta * g.transverse * delta;
    at(out, a) += y;
    at(out, b) -= y;
  }
  if (m.has_volume() && beta != 0) {
    const bool nodal = m.has_nodal_volume();
    if (nodal) tet_scratch_.resize(m.ntet()), node_scratch_.assign(n, 0.0);
    for (int32_t e = 0; e < m.ntet(); ++e) {
      const Tet& tet = m.tet_points[e];
      double s = 0;
      for (int i = 0; i < 4; ++i) s += volume_gradient_[e][i].dot(at(p, tet[i]));
      if (nodal) {
        tet_scratch_[e] = s;
        continue;
      }
      for (int i = 0; i < 4; ++i) at(out, tet[i]) += beta * m.tet_k[e] * s * volume_gradient_[e][i];
    }
    if (nodal) {
      // dV_a . p = sum over a's tets of dV_t . p / 4; then each tet's corners
      // receive the mean of its nodes' k_a (dV_a . p) along dV_t/dx_i.
      for (int32_t a = 0; a < n; ++a) {
        double s = 0;
        for (int32_t e : tets_of_point_[a]) s += tet_scratch_[e];
        node_scratch_[a] = m.point_volume_k[a] * s / 4;
      }
      for (int32_t e = 0; e < m.ntet(); ++e) {
        const Tet& tet = m.tet_points[e];
        const double c = (node_scratch_[tet[0]] + node_scratch_[tet[1]] + node_scratch_[tet[2]] + node_scratch_[tet[3]]) / 4;
        for (int i = 0; i < 4; ++i) at(out, tet[i]) += beta * c * volume_gradient_[e][i];
      }
    }
  }
  if (m.has_shear_element()) {
    if (beta != 0) out.noalias() += beta * (shear_k_ * p);
    if (alpha != 0 && m.shear_damping_time > 0) out.noalias() += alpha * (shear_d_ * p);
  }
  if (beta != 0)
    for (const ContactBlock& c : contact_) {
      Vec3 wp = Vec3::Zero();
      for (int j = 0; j < 3; ++j)
        if (c.point[j] >= 0) wp += c.w[j] * at(p, c.point[j]);
      const Vec3 y = beta * (c.k * wp);
      for (int i = 0; i < 3; ++i)
        if (c.point[i] >= 0) at(out, c.point[i]) += c.w[i] * y;
    }
}

void ImplicitSystem::diagonal_blocks(double m_coef, double alpha, double beta, std::vector<Eigen::Matrix3d>& out) const {
  const Model& m = model_;
  const int32_t n = m.npoint();
  out.resize(n);
  for (int32_t i = 0; i < n; ++i)
    out[i] = (m_coef + alpha * m.viscous_damping) * m.mass[i] * Eigen::Matrix3d::Identity();
  for (int32_t s = 0; s < m.nspring(); ++s) {
    const SpringTangent& g = springs_[s];
    const Eigen::Matrix3d block = (alpha * g.d + beta * g.axial) * g.u * g.u.transpose() +
                                  beta * g.transverse * Eigen::Matrix3d::Identity();
    out[m.spring_ends[s][0]] += block;
    out[m.spring_ends[s][1]] += block;
  }
  if (m.has_volume() && m.has_nodal_volume() && beta != 0) {
    // Node a's row of G at each point q of its patch: the sum over the tets
    // of a holding q of dV_t/dx_q / 4, accumulated per point id.
    // Scratch kept between calls (zero again after each node): no allocation per step.
    std::vector<Vec3>& row = row_scratch_;
    std::vector<uint8_t>& in_patch = patch_mark_;
    std::vector<int32_t>& patch = patch_scratch_;
    row.resize(n, Vec3::Zero());
    in_patch.resize(n, 0);
    for (int32_t a = 0; a < n; ++a) {
      patch.clear();
      for (int32_t e : tets_of_point_[a])
        for (int i = 0; i < 4; ++i) {
          const int32_t q = m.tet_points[e][i];
          if (!in_patch[q]) in_patch[q] = 1, patch.push_back(q);
          row[q] += volume_gradient_[e][i] / 4;
        }
      for (int32_t q : patch) {
        out[q] += beta * m.point_volume_k[a] * row[q] * row[q].transpose();
        row[q].setZero();
        in_patch[q] = 0;
      }
    }
  } else if (m.has_volume() && beta != 0) {
    for (int32_t e = 0; e < m.ntet(); ++e)
      for (int i = 0; i < 4; ++i) {
        const Vec3& g = volume_gradient_[e][i];
        out[m.tet_points[e][i]] += beta * m.tet_k[e] * g * g.transpose();
      }
  }
  if (m.has_shear_element()) {
    const double damp = m.shear_damping_time > 0 ? alpha : 0;
    using Matrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;
    for (const auto& [matrix, coef] : {std::pair<const Matrix*, double>{&shear_k_, beta}, {&shear_d_, damp}}) {
      if (coef == 0) continue;
      for (int32_t r = 0; r < 3 * n; ++r)
        for (Matrix::InnerIterator it(*matrix, r); it; ++it)
          if (it.col() / 3 == r / 3) out[r / 3](r % 3, it.col() % 3) += coef * it.value();
    }
  }
  for (const ContactBlock& c : contact_)
    for (int i = 0; i < 3; ++i)
      if (c.point[i] >= 0) out[c.point[i]] += beta * c.w[i] * c.w[i] * c.k;
}

}  // namespace organsim
