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

// Updates of the scale d (gershgorin_rows). On the 7656-point liver the
// guaranteed step rises from 0.474 ms at d = 1 to 0.512 ms after 20 and
// 0.513 ms after 60 (docs/stability.md); each costs a pass over the rows.
constexpr int kScaleIterations = 20;

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

template <class Visit>
void for_each_tet_of(const Model& model, int32_t p, Visit&& visit) {
  const GatherLayout& layout = model.layout;
  const int32_t c = layout.chunk_size;
  const int32_t first = layout.tets.chunk_offset[p / c] + p % c;
  for (int32_t j = 0; j < layout.tets.count[p]; ++j) visit(layout.tets.item[first + j * c]);
}

// One point of a node's patch: its vector v_c (G_ac for the nodal volume
// term, w_c for a smoothed shear patch) and |v_c|.
struct PatchEntry {
  int32_t point = 0;
  Vec3 v{0, 0, 0};
  double norm = 0;
};

// The nodal volume term's node a: K_a = k_a G_a G_a^T with G_aj = dV_a/dx_j
// = the sum of g_tj / 4 over the tets t of a holding j, one entry per point
// of a's tets. `slot` (npoint, all -1) finds a point's entry; it is left
// all -1 again.
std::vector<PatchEntry> nodal_volume_patch(const Model& model, int32_t a, std::vector<int32_t>& slot) {
  std::vector<PatchEntry> patch;
  for_each_tet_of(model, a, [&](int32_t t) {
    const Tet& tet = model.tet_points[t];
    for (int c = 0; c < 4; ++c) {
      const Vec3 g = volume_gradient(model, tet, c) / 4;
      if (slot[tet[c]] < 0) {
        slot[tet[c]] = static_cast<int32_t>(patch.size());
        patch.push_back({tet[c], g, 0});
      } else {
        patch[slot[tet[c]]].v += g;
      }
    }
  });
  for (PatchEntry& e : patch) e.norm = e.v.norm(), slot[e.point] = -1;
  return patch;
}

std::vector<PatchEntry> shear_patch(const Model& model, int32_t a) {
  std::vector<PatchEntry> patch;
  for (const ShearPatchEntry& e : smoothed_shear_patch(model, a)) patch.push_back({e.point, e.w, e.w.norm()});
  return patch;
}

// sum_c |v_c| z_c over a patch: T_a of its node (up to the node's factor).
double weighed(const std::vector<PatchEntry>& patch, const std::vector<double>& z) {
  double sum = 0;
  for (const PatchEntry& e : patch) sum += e.norm * z[e.point];
  return sum;
}

// The patches of the nodes a pass needs (and the volume patches' sums for
// one z), each built once for all the rows that read it.
struct NodePatches {
  std::vector<std::vector<PatchEntry>> volume, shear;  // (npoint) or empty; empty patches where not needed
  std::vector<double> volume_sum;                      // weighed() of each volume patch
  std::vector<std::vector<int32_t>> nodes;             // nodes_of each row's point (npoint), or empty

  void weigh(const std::vector<double>& z) {
    volume_sum.resize(volume.size());
    for (size_t a = 0; a < volume.size(); ++a) volume_sum[a] = weighed(volume[a], z);
  }
};

// The nodes whose patch may hold point i: the points of i's tets.
std::vector<int32_t> nodes_of(const Model& model, int32_t i) {
  std::vector<int32_t> nodes;
  for_each_tet_of(model, i, [&](int32_t t) {
    for (int32_t a : model.tet_points[t])
      if (std::find(nodes.begin(), nodes.end(), a) == nodes.end()) nodes.push_back(a);
  });
  return nodes;
}

// The patches that the rows of `points` read (every point's: nullptr), and
// those points' nodes.
NodePatches node_patches(const Model& model, const std::vector<int32_t>* points) {
  NodePatches p;
  if (!model.has_nodal_volume() && !model.has_smoothed_shear()) return p;
  std::vector<uint8_t> needed(model.npoint(), 0);
  std::vector<int32_t> slot(model.npoint(), -1);
  p.nodes.resize(model.npoint());
  auto row = [&](int32_t i) {
    p.nodes[i] = nodes_of(model, i);
    for (int32_t a : p.nodes[i]) needed[a] = 1;
  };
  if (points) {
    for (int32_t i : *points) row(i);
  } else {
    for (int32_t i = 0; i < model.npoint(); ++i) row(i);
  }
  if (model.has_nodal_volume()) p.volume.resize(model.npoint());
  if (model.has_smoothed_shear()) p.shear.resize(model.npoint());
  for (int32_t a = 0; a < model.npoint(); ++a) {
    if (!needed[a]) continue;
    if (model.has_nodal_volume()) p.volume[a] = nodal_volume_patch(model, a, slot);
    if (model.has_smoothed_shear()) p.shear[a] = shear_patch(model, a);
  }
  return p;
}

// Which sum an element's block goes to: the springs (damped), the per-tet
// shear element at full k_t (damped when it has its damper, elastic at
// 1 - s of it), everything else (volume terms, smoothed shear patches).
enum class Part { Springs, Shear, Other };

// Calls visit(part, block) for every element e holding point i (free), with
// block = the (i, i) block of e's block-diagonal majorant (gershgorin.h):
// f K_e,ii for the springs and volume terms, whose forms are rank one
// (f = T_e / tau_ei = sum_c |v_c| z_c / (|v_i| z_i) over the element's
// points c, |v_c| the length of c's part of the form); K_e,ii + sum_c
// ||K_e,ic|| z_c / z_i I for the shear forms. z = d / sqrt(m), 0 at fixed
// points (the element's forms never see them). `cache` holds the patches
// of i's nodes, the volume patches weighed with this z.
template <class Visit>
void visit_row_elements(const Model& model, int32_t i, const std::vector<double>& z, const NodePatches& cache,
                        Visit&& visit) {
  const GatherLayout& layout = model.layout;
  const int32_t c = layout.chunk_size;
  const auto& X = model.rest_position;
  const double zi = z[i];
  const int32_t first_spring = layout.springs.chunk_offset[i / c] + i % c;
  for (int32_t j = 0; j < layout.springs.count[i]; ++j) {
    const int32_t e = first_spring + j * c;
    const int32_t s = layout.springs.item[e], other = layout.spring_other[e];
    const Vec3 l = X[other] - X[i];
    const double n = l.norm();
    if (!(n > 0) || !(model.spring_k[s] > 0)) continue;  // coincident ends: no direction, no stiffness (as critical_step.cpp)
    visit(Part::Springs, Mat3((1 + z[other] / zi) * force_law::spring_rest_stiffness(model.spring_k[s], Vec3(l / n))));
  }
  // A tet's four corners: f from their |g_c|.
  auto tet_factor = [&](int32_t t, auto&& gradient, int corner) {
    const Tet& tet = model.tet_points[t];
    double sum = 0;
    for (int m = 0; m < 4; ++m) sum += gradient(m).norm() * z[tet[m]];
    return sum / (gradient(corner).norm() * zi);
  };
  auto corner_of = [&](int32_t t) {
    const Tet& tet = model.tet_points[t];
    return static_cast<int>(std::find(tet.begin(), tet.end(), i) - tet.begin());
  };
  static const std::vector<int32_t> kNoNodes;  // without node terms
  const std::vector<int32_t>& nodes = cache.nodes.empty() ? kNoNodes : cache.nodes[i];
  auto node_term = [&](const std::vector<PatchEntry>& patch, double sum, double k) {
    const auto self = std::find_if(patch.begin(), patch.end(), [&](const PatchEntry& e) { return e.point == i; });
    if (self == patch.end() || !(k > 0) || !(self->norm > 0)) return;
    visit(Part::Other, Mat3(sum / (self->norm * zi) * force_law::volume_rest_stiffness(k, self->v, self->v)));
  };
  // A shear form's block (i, c) is k ((g_i . g_c) I + g_c g_i^T), of norm
  // at most k (|g_i . g_c| + |g_i| |g_c|): its Gershgorin majorant.
  auto shear_term = [&](const Vec3& gi, double k, auto&& others) {
    double off = 0;
    others([&](int32_t p, const Vec3& g) { off += (std::abs(gi.dot(g)) + gi.norm() * g.norm()) * z[p]; });
    return Mat3(k * (force_law::shear_rest_stiffness(gi, gi) + off / zi * Mat3::Identity()));
  };
  if (model.has_nodal_volume()) {
    for (int32_t a : nodes) node_term(cache.volume[a], cache.volume_sum[a], model.point_volume_k[a]);
  } else if (model.has_volume()) {
    for_each_tet_of(model, i, [&](int32_t t) {
      const int corner = corner_of(t);
      const auto gradient = [&](int m) { return volume_gradient(model, model.tet_points[t], m); };
      const Vec3 gi = gradient(corner);
      if (model.tet_k[t] > 0 && gi.squaredNorm() > 0)
        visit(Part::Other, Mat3(tet_factor(t, gradient, corner) * force_law::volume_rest_stiffness(model.tet_k[t], gi, gi)));
    });
  }
  if (model.has_shear_element()) {
    for_each_tet_of(model, i, [&](int32_t t) {
      const int corner = corner_of(t);
      const Tet& tet = model.tet_points[t];
      const auto& g = model.tet_shape_gradient[t];
      if (model.tet_shear_k[t] > 0)
        visit(Part::Shear, shear_term(g[corner], model.tet_shear_k[t], [&](auto&& other) {
                for (int m = 0; m < 4; ++m)
                  if (m != corner) other(tet[m], g[m]);
              }));
    });
  }
  if (model.has_smoothed_shear()) {
    for (int32_t a : nodes) {
      const std::vector<PatchEntry>& patch = cache.shear[a];
      const auto self = std::find_if(patch.begin(), patch.end(), [&](const PatchEntry& e) { return e.point == i; });
      const double k = smoothed_shear_patch_k(model, a);
      if (self != patch.end() && k > 0)
        visit(Part::Other, shear_term(self->v, k, [&](auto&& other) {
                for (const PatchEntry& e : patch)
                  if (e.point != i) other(e.point, e.v);
              }));
    }
  }
}

// z = d / sqrt(m) at the free points, 0 at the fixed ones.
std::vector<double> scaled_inverse_sqrt_mass(const Model& model, const std::vector<double>& scale) {
  std::vector<double> z(model.npoint(), 0.0);
  for (int32_t p = 0; p < model.npoint(); ++p)
    if (model.inv_mass[p] > 0) z[p] = scale[p] * std::sqrt(model.inv_mass[p]);
  return z;
}

void compute_row(const Model& model, int32_t i, const std::vector<double>& z, const NodePatches& cache,
                 GershgorinRows& rows) {
  rows.all[i] = rows.damped[i] = 0;
  if (model.inv_mass[i] <= 0) return;
  Mat3 springs = Mat3::Zero(), shear = Mat3::Zero(), other = Mat3::Zero();
  visit_row_elements(model, i, z, cache, [&](Part part, const Mat3& block) {
    (part == Part::Springs ? springs : part == Part::Shear ? shear : other) += block;
  });
  rows.all[i] = largest_eigenvalue_from_above(springs + other + (1 - model.shear_smoothed_share) * shear);
  rows.damped[i] = largest_eigenvalue_from_above(model.shear_damping_time > 0 ? Mat3(springs + shear) : springs);
}

// The tool's k_c s_i on the points `options` lets it touch, N/m (npoint).
std::vector<double> tool_stiffness(const Model& model, const CriticalStepOptions& options) {
  const int32_t n = model.npoint();
  if (options.tool_contact_stiffness > 0 && !options.tool_may_touch.empty() &&
      options.tool_may_touch.size() != static_cast<size_t>(n))
    throw Error(ErrorKind::Usage, "gershgorin_bounds: tool_may_touch has " +
                                      std::to_string(options.tool_may_touch.size()) + " entries, expected " +
                                      std::to_string(n));
  std::vector<double> k(n, 0.0);
  if (options.tool_contact_stiffness > 0)
    for (int32_t i = 0; i < n; ++i)
      if (options.tool_may_touch.empty() || options.tool_may_touch[i])
        k[i] = options.tool_contact_stiffness * model.tool_scale(i);
  return k;
}

void check_layout(const Model& model) {
  // The rows walk each point's springs and tets through the gather layout.
  if (model.layout.springs.count.size() != static_cast<size_t>(model.npoint()) ||
      model.layout.tets.count.size() != static_cast<size_t>(model.npoint()))
    throw Error(ErrorKind::Usage, "gershgorin_rows: the Model's gather layout covers " +
                                      std::to_string(model.layout.springs.count.size()) + " points, expected " +
                                      std::to_string(model.npoint()) + " (build_gather_layout)");
}

GershgorinRows rows_with_scale(const Model& model, std::vector<double> scale, NodePatches& cache) {
  GershgorinRows rows;
  rows.all.assign(model.npoint(), 0.0);
  rows.damped.assign(model.npoint(), 0.0);
  rows.scale = std::move(scale);
  const std::vector<double> z = scaled_inverse_sqrt_mass(model, rows.scale);
  cache.weigh(z);
  for (int32_t i = 0; i < model.npoint(); ++i) compute_row(model, i, z, cache, rows);
  return rows;
}

}  // namespace

void compute_gershgorin_rows(const Model& model, const std::vector<int32_t>& points, GershgorinRows& rows) {
  const std::vector<double> z = scaled_inverse_sqrt_mass(model, rows.scale);
  NodePatches cache = node_patches(model, &points);
  cache.weigh(z);
  for (int32_t i : points) compute_row(model, i, z, cache, rows);
}

GershgorinRows gershgorin_rows(const Model& model, const CriticalStepOptions& options) {
  check_layout(model);
  NodePatches cache = node_patches(model, nullptr);
  const std::vector<double> tool = tool_stiffness(model, options);
  // Start from d = 1 and multiply each d_i by its point's bound. Were the
  // rows the scalar sums sum_e lambda_max(D_e,ii) (the Gershgorin form), this
  // would be the power iteration towards the Perron vector of that
  // non-negative matrix, whose rows all equal its spectral radius; on the
  // matrix rows it raises d where a row is above the rest, which lowers that
  // row and raises its neighbours'. Every iterate is a proof; the one whose
  // step is largest is kept (on the liver the step still rose after 60
  // updates, but the power iteration towards the scalar Perron vector itself
  // localises d on the stiffest points and loosens the matrix rows again).
  std::vector<double> scale(model.npoint(), 0.0);
  for (int32_t i = 0; i < model.npoint(); ++i) scale[i] = model.inv_mass[i] > 0 ? 1.0 : 0.0;
  GershgorinRows best = rows_with_scale(model, scale, cache);
  double best_step = guaranteed_critical_step(model, best, options);
  GershgorinRows rows = best;
  for (int it = 0; it < kScaleIterations; ++it) {
    double largest = 0;
    for (int32_t i = 0; i < model.npoint(); ++i) {
      // A point without stiffness keeps its scale: any positive d is valid.
      const double bound = (rows.all[i] + tool[i]) * model.inv_mass[i];
      if (bound > 0) scale[i] *= bound;
      largest = std::max(largest, scale[i]);
    }
    if (!(largest > 0)) break;
    for (double& d : scale) d /= largest;
    rows = rows_with_scale(model, scale, cache);
    const double step = guaranteed_critical_step(model, rows, options);
    if (step > best_step) best_step = step, best = rows;
  }
  return best;
}

GershgorinRows gershgorin_rows_with_scale(const Model& model, std::vector<double> scale) {
  check_layout(model);
  if (scale.size() != static_cast<size_t>(model.npoint()))
    throw Error(ErrorKind::Usage, "gershgorin_rows_with_scale: " + std::to_string(scale.size()) +
                                      " scales, expected " + std::to_string(model.npoint()));
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (model.inv_mass[i] > 0 && !(scale[i] > 0 && std::isfinite(scale[i])))
      throw Error(ErrorKind::Usage, "gershgorin_rows_with_scale: scale " + std::to_string(scale[i]) + " at point " +
                                        std::to_string(i) + ", expected a positive finite number at every free point");
  NodePatches cache = node_patches(model, nullptr);
  return rows_with_scale(model, std::move(scale), cache);
}

std::vector<double> gershgorin_bounds(const Model& model, const GershgorinRows& rows,
                                      const CriticalStepOptions& options) {
  const std::vector<double> tool = tool_stiffness(model, options);
  std::vector<double> bound(model.npoint(), 0.0);
  // The tool adds k_c I to A_i: lambda_max shifts by k_c.
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (model.inv_mass[i] > 0) bound[i] = (rows.all[i] + tool[i]) * model.inv_mass[i];
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
