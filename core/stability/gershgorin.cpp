#include "core/stability/gershgorin.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/model/shear_element.h"
#include "core/physics/force_law.h"
#include "core/util/error.h"

namespace organsim {

namespace {

using Mat3 = Eigen::Matrix3d;

// dV/dx_c of a tet at rest, for its corner c.
Vec3 volume_gradient(const Model& model, const Tet& tet, int c) {
  const auto& X = model.rest_position;
  // The gradient of the signed volume with respect to a vertex is the
  // opposite face's area-weighted normal / 3, pointing towards that vertex.
  static constexpr int kFace[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};
  const Vec3& a = X[tet[kFace[c][0]]];
  const Vec3& b = X[tet[kFace[c][1]]];
  const Vec3& d = X[tet[kFace[c][2]]];
  return (b - a).cross(d - a) / 6.0;
}

// lambda_max of a symmetric positive semi-definite 3x3 matrix, from above:
// the closed-form eigenvalue plus a margin for its rounding (1e-7 of the
// trace, far above the method's error), capped by the trace (the sum of the
// non-negative eigenvalues).
double largest_eigenvalue_from_above(const Mat3& a) {
  const double trace = a.trace();
  if (!(trace > 0)) return 0;
  Eigen::SelfAdjointEigenSolver<Mat3> solver;
  solver.computeDirect(a, Eigen::EigenvaluesOnly);
  return std::min(trace, solver.eigenvalues()(2) + 1e-7 * trace);
}

}  // namespace

void compute_gershgorin_row(const Model& model, int32_t i, GershgorinRows& rows) {
  rows.all[i] = rows.damped[i] = 0;
  if (model.inv_mass[i] <= 0) return;
  auto free = [&](int32_t j) { return model.inv_mass[j] > 0; };
  // sqrt(m_i / m_j): the row of M^-1/2 K M^-1/2, scaled back by m_i.
  auto weight = [&](int32_t j) { return std::sqrt(model.mass[i] / model.mass[j]); };
  const GatherLayout& layout = model.layout;
  const int32_t c = layout.chunk_size;
  const auto& X = model.rest_position;

  Mat3 diag_springs = Mat3::Zero();
  double off_springs = 0;
  const int32_t first_spring = layout.springs.chunk_offset[i / c] + i % c;
  for (int32_t j = 0; j < layout.springs.count[i]; ++j) {
    const int32_t e = first_spring + j * c;
    const int32_t s = layout.springs.item[e], other = layout.spring_other[e];
    const Vec3 l = X[other] - X[i];
    const double n = l.norm();
    if (!(n > 0)) continue;  // coincident ends: no direction, no stiffness (as critical_step.cpp)
    const Vec3 u = l / n;
    diag_springs += force_law::spring_rest_stiffness(model.spring_k[s], u);
    if (free(other)) off_springs += model.spring_k[s] * weight(other);
  }

  Mat3 diag = diag_springs;
  double off = off_springs;
  auto tets_of = [&](int32_t p, auto&& visit) {
    const int32_t first = layout.tets.chunk_offset[p / c] + p % c;
    for (int32_t j = 0; j < layout.tets.count[p]; ++j) visit(layout.tets.item[first + j * c]);
  };
  if (model.has_nodal_volume()) {
    // K_ij = sum_a k_a G_ai G_aj^T with G_ai = dV_a/dx_i = sum of g_ti / 4
    // over the tets holding a and i: the nodes a are the points of i's tets.
    // ||K_ij|| <= sum_a |k_a| |G_ai| |G_aj| and |G_aj| <= sum of |g_tj| / 4
    // over the tets of a holding j, so a adds |k_a| |G_ai| times the weighted
    // sum of its tets' other free gradients / 4.
    std::vector<std::pair<int32_t, Vec3>> nodes;  // (a, G_ai)
    tets_of(i, [&](int32_t t) {
      const Tet& tet = model.tet_points[t];
      const int corner = static_cast<int>(std::find(tet.begin(), tet.end(), i) - tet.begin());
      const Vec3 gi = volume_gradient(model, tet, corner) / 4;
      for (int32_t a : tet) {
        auto it = std::find_if(nodes.begin(), nodes.end(), [&](const auto& n) { return n.first == a; });
        if (it == nodes.end()) nodes.emplace_back(a, gi);
        else it->second += gi;
      }
    });
    for (const auto& [a, g] : nodes) {
      const double k = model.point_volume_k[a];
      diag += force_law::volume_rest_stiffness(k, g, g);
      double reach = 0;
      tets_of(a, [&](int32_t t) {
        const Tet& tet = model.tet_points[t];
        for (int m = 0; m < 4; ++m)
          if (tet[m] != i && free(tet[m])) reach += volume_gradient(model, tet, m).norm() / 4 * weight(tet[m]);
      });
      off += std::abs(k) * g.norm() * reach;
    }
  } else if (model.has_volume()) {
    const int32_t first_tet = layout.tets.chunk_offset[i / c] + i % c;
    for (int32_t j = 0; j < layout.tets.count[i]; ++j) {
      const int32_t t = layout.tets.item[first_tet + j * c];
      const Tet& tet = model.tet_points[t];
      const int corner = static_cast<int>(std::find(tet.begin(), tet.end(), i) - tet.begin());
      const Vec3 gi = volume_gradient(model, tet, corner);
      diag += force_law::volume_rest_stiffness(model.tet_k[t], gi, gi);
      for (int k = 0; k < 4; ++k)
        if (k != corner && free(tet[k]))
          off += model.tet_k[t] * gi.norm() * volume_gradient(model, tet, k).norm() * weight(tet[k]);
    }
  }
  // The per-tet shear element's blocks at full k_t: (1 - s) of them are
  // elastic, all of them the damper's (over tau).
  Mat3 diag_shear = Mat3::Zero();
  double off_shear = 0;
  if (model.has_shear_element()) {
    // K_ij = k_t ((g_i . g_j) I + g_j g_i^T) per tet: ||K_ij|| <= k_t (|g_i . g_j| + |g_i| |g_j|).
    const int32_t first_tet = layout.tets.chunk_offset[i / c] + i % c;
    for (int32_t j = 0; j < layout.tets.count[i]; ++j) {
      const int32_t t = layout.tets.item[first_tet + j * c];
      const Tet& tet = model.tet_points[t];
      const int corner = static_cast<int>(std::find(tet.begin(), tet.end(), i) - tet.begin());
      const Vec3& gi = model.tet_shape_gradient[t][corner];
      diag_shear += shear_element_rest_block(model, t, corner, corner);
      for (int k = 0; k < 4; ++k) {
        const Vec3& gk = model.tet_shape_gradient[t][k];
        if (k != corner && free(tet[k]))
          off_shear += model.tet_shear_k[t] * (std::abs(gi.dot(gk)) + gi.norm() * gk.norm()) * weight(tet[k]);
      }
    }
  }
  if (model.has_smoothed_shear()) {
    // Node patches: block (i, j) from node a is k_a ((w_ai . w_aj) I +
    // w_aj w_ai^T), ||.|| <= 2 k_a |w_ai| |w_aj|; the nodes a whose patch
    // holds i are the points of i's tets.
    std::vector<int32_t> nodes;
    tets_of(i, [&](int32_t t) {
      for (int32_t a : model.tet_points[t])
        if (std::find(nodes.begin(), nodes.end(), a) == nodes.end()) nodes.push_back(a);
    });
    for (int32_t a : nodes) {
      const double k = smoothed_shear_patch_k(model, a);
      const std::vector<ShearPatchEntry> patch = smoothed_shear_patch(model, a);
      const auto self = std::find_if(patch.begin(), patch.end(), [&](const ShearPatchEntry& e) { return e.point == i; });
      if (self == patch.end()) continue;
      const Vec3& wi = self->w;
      diag += k * force_law::shear_rest_stiffness(wi, wi);
      for (const ShearPatchEntry& e : patch)
        if (e.point != i && free(e.point)) off += 2 * k * wi.norm() * e.w.norm() * weight(e.point);
    }
  }
  const double per_tet_share = 1 - model.shear_smoothed_share;
  rows.all[i] = largest_eigenvalue_from_above(diag + per_tet_share * diag_shear) + off + per_tet_share * off_shear;
  rows.damped[i] = model.shear_damping_time > 0
                       ? largest_eigenvalue_from_above(diag_springs + diag_shear) + off_springs + off_shear
                       : largest_eigenvalue_from_above(diag_springs) + off_springs;
}

GershgorinRows gershgorin_rows(const Model& model) {
  // The rows walk each point's springs and tets through the gather layout.
  if (model.layout.springs.count.size() != static_cast<size_t>(model.npoint()) ||
      model.layout.tets.count.size() != static_cast<size_t>(model.npoint()))
    throw Error(ErrorKind::Usage, "gershgorin_rows: the Model's gather layout covers " +
                                      std::to_string(model.layout.springs.count.size()) + " points, expected " +
                                      std::to_string(model.npoint()) + " (build_gather_layout)");
  GershgorinRows rows;
  rows.all.assign(model.npoint(), 0.0);
  rows.damped.assign(model.npoint(), 0.0);
  for (int32_t i = 0; i < model.npoint(); ++i) compute_gershgorin_row(model, i, rows);
  return rows;
}

std::vector<double> gershgorin_bounds(const Model& model, const GershgorinRows& rows,
                                      const CriticalStepOptions& options) {
  const int32_t n = model.npoint();
  if (options.tool_contact_stiffness > 0 && !options.tool_may_touch.empty() &&
      options.tool_may_touch.size() != static_cast<size_t>(n))
    throw Error(ErrorKind::Usage, "gershgorin_bounds: tool_may_touch has " +
                                      std::to_string(options.tool_may_touch.size()) + " entries, expected " +
                                      std::to_string(n));
  std::vector<double> bound(n, 0.0);
  for (int32_t i = 0; i < n; ++i) {
    if (model.inv_mass[i] <= 0) continue;
    const bool touched = options.tool_contact_stiffness > 0 &&
                         (options.tool_may_touch.empty() || options.tool_may_touch[i]);
    // The tool adds k_c I to the diagonal block: lambda_max shifts by k_c.
    const double tool = touched ? options.tool_contact_stiffness * model.tool_scale(i) : 0.0;
    bound[i] = (rows.all[i] + tool) * model.inv_mass[i];
  }
  return bound;
}

double spring_damping_time(const Model& model) {
  double c = 0;
  for (int32_t s = 0; s < model.nspring(); ++s)
    if (model.spring_k[s] > 0) c = std::max(c, model.spring_d[s] / model.spring_k[s]);
  return c;
}

double damping_time(const Model& model) { return std::max(spring_damping_time(model), model.shear_damping_time); }

double guaranteed_critical_step(const Model& model, const GershgorinRows& rows, const CriticalStepOptions& options) {
  const std::vector<double> bound = gershgorin_bounds(model, rows, options);
  const double lambda = bound.empty() ? 0 : *std::max_element(bound.begin(), bound.end());
  double lambda_damped = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) lambda_damped = std::max(lambda_damped, rows.damped[i] * model.inv_mass[i]);
  return critical_step_for_mode(lambda, damping_time(model) * lambda_damped + model.viscous_damping);
}

}  // namespace organsim
