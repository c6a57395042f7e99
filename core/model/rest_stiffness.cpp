#include "core/model/rest_stiffness.h"

#include <array>

#include "core/model/shear_element.h"
#include "core/physics/force_law.h"

namespace organsim {

namespace {

// Adds the 3x3 block `b` at points (p, q).
void add_block(Triplets& t, int32_t p, int32_t q, const Eigen::Matrix3d& b) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) t.emplace_back(3 * p + i, 3 * q + j, b(i, j));
}

// A spring's block between its ends: +b on the diagonal, -b off it.
void add_spring_block(Triplets& t, int32_t a, int32_t b, const Eigen::Matrix3d& block) {
  add_block(t, a, a, block);
  add_block(t, b, b, block);
  add_block(t, a, b, -block);
  add_block(t, b, a, -block);
}

Vec3 rest_direction(const Model& model, int32_t s) {
  const auto [a, b] = model.spring_ends[s];
  return (model.rest_position[b] - model.rest_position[a]).normalized();
}

}  // namespace

// Volume per tet: f_i = k_v (V_r - V) g_i, so at rest d f_i / d x_j = -k_v g_i g_j^T.
Triplets rest_stiffness(const Model& model, RestTerms terms) {
  Triplets t;
  const bool all = terms == RestTerms::All;
  if (all) t.reserve(static_cast<size_t>(model.nspring()) * 36 + (model.has_volume() ? model.ntet() * 144 : 0));
  const auto& x = model.rest_position;
  for (int32_t s = 0; all && s < model.nspring(); ++s) {
    const auto [a, b] = model.spring_ends[s];
    add_spring_block(t, a, b, force_law::spring_rest_stiffness(model.spring_k[s], rest_direction(model, s)));
  }
  // Shear element: (1 - s) k_t ((g_i . g_j) I + g_j g_i^T) per tet and, with
  // a smoothed share s, its node patches (core/model/shear_element.h).
  const double per_tet_share = 1 - model.shear_smoothed_share;
  for (int32_t e = 0; e < static_cast<int32_t>(model.tet_shear_k.size()); ++e)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        add_block(t, model.tet_points[e][i], model.tet_points[e][j],
                  per_tet_share * shear_element_rest_block(model, e, i, j));
  if (model.has_smoothed_shear())
    for (int32_t a = 0; a < model.npoint(); ++a) {
      const double k = smoothed_shear_patch_k(model, a);
      const std::vector<ShearPatchEntry> patch = smoothed_shear_patch(model, a);
      for (const ShearPatchEntry& p : patch)
        for (const ShearPatchEntry& q : patch)
          add_block(t, p.point, q.point, k * force_law::shear_rest_stiffness(p.w, q.w));
    }
  if (!all || !model.has_volume()) return t;
  // Nodal: the energy k_a/2 (V_a - V_a^r)^2 gives G^T diag(k_a) G with
  // G = dV_a/dx (npoint x 3 npoint, row a = sum over the tets of a of their
  // gradients / 4): it couples all points of a node patch.
  Triplets g_rows;
  for (int32_t e = 0; e < model.ntet(); ++e) {
    const Tet& tet = model.tet_points[e];
    const Vec3 a = x[tet[1]] - x[tet[0]], b = x[tet[2]] - x[tet[0]], c = x[tet[3]] - x[tet[0]];
    std::array<Vec3, 4> g;
    g[1] = b.cross(c) / 6;
    g[2] = c.cross(a) / 6;
    g[3] = a.cross(b) / 6;
    g[0] = -(g[1] + g[2] + g[3]);
    if (model.has_nodal_volume()) {
      for (int32_t node : tet)
        for (int i = 0; i < 4; ++i)
          for (int k = 0; k < 3; ++k) g_rows.emplace_back(node, 3 * tet[i] + k, g[i][k] / 4);
      continue;
    }
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) add_block(t, tet[i], tet[j], force_law::volume_rest_stiffness(model.tet_k[e], g[i], g[j]));
  }
  if (model.has_nodal_volume()) {
    const int32_t n = model.npoint();
    Eigen::SparseMatrix<double> G(n, 3 * n);
    G.setFromTriplets(g_rows.begin(), g_rows.end());
    const Eigen::Map<const Eigen::VectorXd> k(model.point_volume_k.data(), n);
    const Eigen::SparseMatrix<double> K = G.transpose() * (k.asDiagonal() * G);
    for (int32_t col = 0; col < K.outerSize(); ++col)
      for (Eigen::SparseMatrix<double>::InnerIterator it(K, col); it; ++it)
        t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
  }
  return t;
}

Triplets rest_damping(const Model& model, RestTerms terms) {
  Triplets t;
  const bool all = terms == RestTerms::All;
  if (all) t.reserve(static_cast<size_t>(model.nspring()) * 36 + 3 * static_cast<size_t>(model.npoint()));
  for (int32_t s = 0; all && s < model.nspring(); ++s) {
    const auto [a, b] = model.spring_ends[s];
    add_spring_block(t, a, b, force_law::spring_rest_stiffness(model.spring_d[s], rest_direction(model, s)));
  }
  if (model.shear_damping_time > 0)
    for (int32_t e = 0; e < static_cast<int32_t>(model.tet_shear_k.size()); ++e)
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
          add_block(t, model.tet_points[e][i], model.tet_points[e][j],
                    model.shear_damping_time * shear_element_rest_block(model, e, i, j));
  if (all && model.viscous_damping > 0)
    for (int32_t p = 0; p < model.npoint(); ++p)
      for (int a = 0; a < 3; ++a) t.emplace_back(3 * p + a, 3 * p + a, model.viscous_damping * model.mass[p]);
  return t;
}

Triplets lumped_mass(const Model& model) {
  Triplets t;
  t.reserve(3 * static_cast<size_t>(model.npoint()));
  for (int32_t p = 0; p < model.npoint(); ++p)
    for (int a = 0; a < 3; ++a) t.emplace_back(3 * p + a, 3 * p + a, model.mass[p]);
  return t;
}

Triplets rest_system(const Model& model, double h, double beta) {
  Triplets t = beta != 0 ? rest_stiffness(model) : Triplets{};
  for (auto& e : t) e = {e.row(), e.col(), beta * e.value()};
  for (const auto& e : rest_damping(model)) t.emplace_back(e.row(), e.col(), h * e.value());
  const Triplets mass = lumped_mass(model);
  t.insert(t.end(), mass.begin(), mass.end());
  return t;
}

Eigen::SparseMatrix<double> assemble(const Model& model, const Triplets& triplets) {
  const int32_t ndof = 3 * model.npoint();
  Eigen::SparseMatrix<double> m(ndof, ndof);
  m.setFromTriplets(triplets.begin(), triplets.end());
  return m;
}

}  // namespace organsim
