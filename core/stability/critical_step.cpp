#include "core/stability/critical_step.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/model/shear_element.h"
#include "core/stability/gershgorin.h"
#include "core/stability/label_shares.h"
#include "core/util/error.h"

namespace organsim {

namespace {

// Stiffness at rest in a matrix-free form: springs keep their unit rest
// direction, tets the gradient of their signed volume.
struct RestStiffness {
  std::vector<Vec3> spring_dir;               // unit rest direction of each spring (nspring)
  std::vector<std::array<Vec3, 4>> tet_grad;  // dV/dx_i at rest (ntet x 4)
  std::vector<double> tool_k;                 // k_c on the points the tool may touch, else 0 (npoint)
  // The smoothed shear element's node patches (npoint; empty without it),
  // built once for the power iterations' many products.
  std::vector<std::vector<ShearPatchEntry>> shear_patch;
};

// Gradient of the signed volume V = (x1-x0).((x2-x0)x(x3-x0))/6.
std::array<Vec3, 4> volume_gradient(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
  const Vec3 a = x1 - x0, b = x2 - x0, c = x3 - x0;
  std::array<Vec3, 4> g;
  g[1] = b.cross(c) / 6.0;
  g[2] = c.cross(a) / 6.0;
  g[3] = a.cross(b) / 6.0;
  g[0] = -(g[1] + g[2] + g[3]);
  return g;
}

RestStiffness rest_stiffness(const Model& model, const CriticalStepOptions& options) {
  RestStiffness k;
  const auto& X = model.rest_position;
  k.spring_dir.resize(model.nspring());
  for (int32_t s = 0; s < model.nspring(); ++s) {
    const auto [a, b] = model.spring_ends[s];
    const Vec3 l = X[b] - X[a];
    const double n = l.norm();
    k.spring_dir[s] = n > 0 ? Vec3(l / n) : Vec3::Zero();  // coincident ends: no direction, no stiffness
  }
  if (model.has_volume()) {
    k.tet_grad.resize(model.ntet());
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const Tet& p = model.tet_points[t];
      k.tet_grad[t] = volume_gradient(X[p[0]], X[p[1]], X[p[2]], X[p[3]]);
    }
  }
  if (model.has_smoothed_shear()) {
    k.shear_patch.resize(model.npoint());
    for (int32_t a = 0; a < model.npoint(); ++a) k.shear_patch[a] = smoothed_shear_patch(model, a);
  }
  k.tool_k.assign(model.npoint(), 0.0);
  if (options.tool_contact_stiffness > 0) {
    if (!options.tool_may_touch.empty() && options.tool_may_touch.size() != static_cast<size_t>(model.npoint()))
      throw Error(ErrorKind::Usage, "estimate_critical_step: tool_may_touch has " +
                                        std::to_string(options.tool_may_touch.size()) + " entries, expected " +
                                        std::to_string(model.npoint()));
    for (int32_t i = 0; i < model.npoint(); ++i)
      if (options.tool_may_touch.empty() || options.tool_may_touch[i]) k.tool_k[i] = options.tool_contact_stiffness * model.tool_scale(i);
  }
  return k;
}

// Which terms of K to apply (for the per-term shares of the top mode).
// kShearDamper is the per-tet element at its full k_t, the damper's matrix
// over tau (not part of kAll when the element is smoothed).
enum Terms { kSprings = 1, kVolume = 2, kTool = 4, kShear = 8, kAll = 15, kShearDamper = 16 };

// out = K x for displacements x (fixed points must be zero in x; their rows
// of out are set to zero).
void apply_stiffness(const Model& model, const RestStiffness& k, const std::vector<Vec3>& x,
                     std::vector<Vec3>& out, int terms = kAll) {
  std::fill(out.begin(), out.end(), Vec3::Zero());
  if (terms & kSprings) {
    for (int32_t s = 0; s < model.nspring(); ++s) {
      const auto [a, b] = model.spring_ends[s];
      const Vec3& u = k.spring_dir[s];
      // Energy k/2 (u.(x_b - x_a))^2.
      const Vec3 f = model.spring_k[s] * u.dot(x[b] - x[a]) * u;
      out[a] -= f;
      out[b] += f;
    }
  }
  if ((terms & kVolume) && model.has_nodal_volume()) {
    // Energy k_a/2 (V_a - V_a^r)^2 on nodal volumes: at rest G^T diag(k_a) G,
    // applied as nodal volume changes, nodal pressures, then tet forces.
    std::vector<double> q(model.npoint(), 0.0);
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const Tet& p = model.tet_points[t];
      const auto& g = k.tet_grad[t];
      const double dv = g[0].dot(x[p[0]]) + g[1].dot(x[p[1]]) + g[2].dot(x[p[2]]) + g[3].dot(x[p[3]]);
      for (int i = 0; i < 4; ++i) q[p[i]] += dv / 4;
    }
    for (int32_t a = 0; a < model.npoint(); ++a) q[a] *= model.point_volume_k[a];
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const Tet& p = model.tet_points[t];
      const double s = (q[p[0]] + q[p[1]] + q[p[2]] + q[p[3]]) / 4;
      for (int i = 0; i < 4; ++i) out[p[i]] += s * k.tet_grad[t][i];
    }
  } else if ((terms & kVolume) && model.has_volume()) {
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const Tet& p = model.tet_points[t];
      const auto& g = k.tet_grad[t];
      // Energy k_v/2 (V - V_r)^2: at rest only the Gauss-Newton part k_v g g^T remains.
      const double dv = g[0].dot(x[p[0]]) + g[1].dot(x[p[1]]) + g[2].dot(x[p[2]]) + g[3].dot(x[p[3]]);
      const double s = model.tet_k[t] * dv;
      for (int i = 0; i < 4; ++i) out[p[i]] += s * g[i];
    }
  }
  if (terms & (kShear | kShearDamper)) {
    // Shear element at rest: f_i = sum_j w k_t ((g_i . g_j) I + g_j g_i^T) x_j,
    // w = 1 - s for the elastic part, 1 for the damper's.
    const double w = (terms & kShear ? 1 - model.shear_smoothed_share : 0) + (terms & kShearDamper ? 1 : 0);
    for (int32_t t = 0; t < static_cast<int32_t>(model.tet_shear_k.size()); ++t) {
      const Tet& p = model.tet_points[t];
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) out[p[i]] += w * shear_element_rest_block(model, t, i, j) * x[p[j]];
    }
  }
  if ((terms & kShear) && model.has_smoothed_shear()) {
    // Node patches: block (p, q) = k_a ((w_p . w_q) I + w_q w_p^T), so
    // f_p = k_a (H + H^T) w_p with H = sum_q x_q w_q^T.
    for (int32_t a = 0; a < model.npoint(); ++a) {
      const std::vector<ShearPatchEntry>& patch = k.shear_patch[a];
      Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
      for (const ShearPatchEntry& q : patch) H += x[q.point] * q.w.transpose();
      const Eigen::Matrix3d S = smoothed_shear_patch_k(model, a) * (H + H.transpose());
      for (const ShearPatchEntry& p : patch) out[p.point] += S * p.w;
    }
  }
  if (terms & kTool)
    for (int32_t i = 0; i < model.npoint(); ++i) out[i] += k.tool_k[i] * x[i];
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (model.inv_mass[i] <= 0) out[i].setZero();
}

// Deterministic pseudo-random start vector in [-1, 1] (splitmix64).
double start_component(uint64_t i) {
  uint64_t z = i + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

double dot(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += a[i].dot(b[i]);
  return s;
}

// Smallest interior dihedral angle of a tet, degrees.
double min_dihedral_deg(const std::array<Vec3, 4>& x) {
  double best = 180;
  static const int kEdges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  for (const auto& e : kEdges) {
    const Vec3 axis = (x[e[1]] - x[e[0]]).normalized();
    Vec3 p = x[e[2]] - x[e[0]], q = x[e[3]] - x[e[0]];
    p -= p.dot(axis) * axis;
    q -= q.dot(axis) * axis;
    const double np = p.norm(), nq = q.norm();
    if (np <= 0 || nq <= 0) return 0;
    best = std::min(best, std::acos(std::clamp(p.dot(q) / (np * nq), -1.0, 1.0)) * 180.0 / M_PI);
  }
  return best;
}

SliverTet describe_tet(const Model& model, int32_t t) {
  const Tet& p = model.tet_points[t];
  std::array<Vec3, 4> x;
  for (int i = 0; i < 4; ++i) x[i] = model.rest_position[p[i]];
  double lmax = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) lmax = std::max(lmax, (x[j] - x[i]).norm());
  SliverTet s;
  for (int i = 0; i < 4; ++i) s.points[i] = model.input_of_internal[p[i]];
  s.volume = model.tet_rest_volume[t];
  s.quality = lmax > 0 ? 6.0 * std::sqrt(2.0) * s.volume / (lmax * lmax * lmax) : 0;
  s.min_dihedral_deg = min_dihedral_deg(x);
  return s;
}

// Indices of the `count` largest values (ties by index, deterministic).
std::vector<int32_t> largest(const std::vector<double>& values, int32_t count) {
  std::vector<int32_t> idx(values.size());
  std::iota(idx.begin(), idx.end(), 0);
  const size_t k = std::min(idx.size(), static_cast<size_t>(std::max(count, 0)));
  std::partial_sort(idx.begin(), idx.begin() + k, idx.end(), [&](int32_t a, int32_t b) {
    return values[a] != values[b] ? values[a] > values[b] : a < b;
  });
  idx.resize(k);
  return idx;
}

struct PowerResult {
  double lambda = 0;
  std::vector<Vec3> y;  // unit top eigenvector estimate of W (npoint, zero at fixed points)
  int32_t iterations = 0;
  bool converged = false;
  double residual = 0;  // |W y - lambda y| / lambda
};

// Power iteration on W = M^-1/2 K M^-1/2 (K restricted to `terms`) over the
// free points: y unit, x = M^-1/2 y, W y = M^-1/2 K x. The Rayleigh quotient
// y.Wy rises to lambda_max; stop when it changed by less than the tolerance
// over the last 20 iterations.
PowerResult power_iteration(const Model& model, const RestStiffness& k, const std::vector<double>& inv_sqrt_m,
                            int terms, const CriticalStepOptions& options, double upper_bound) {
  const int32_t n = model.npoint();
  PowerResult r;
  r.y.resize(n);
  std::vector<Vec3> x(n), kx(n), wy(n);
  for (int32_t i = 0; i < n; ++i)
    r.y[i] = inv_sqrt_m[i] > 0 ? Vec3(start_component(3 * i), start_component(3 * i + 1), start_component(3 * i + 2))
                               : Vec3::Zero();
  const double norm = std::sqrt(dot(r.y, r.y));
  if (!(norm > 0) || !(upper_bound > 0)) return r;
  for (auto& v : r.y) v /= norm;
  std::vector<double> history;
  const int32_t window = 20;
  for (int32_t it = 0; it < options.max_iterations; ++it) {
    for (int32_t i = 0; i < n; ++i) x[i] = inv_sqrt_m[i] * r.y[i];
    apply_stiffness(model, k, x, kx, terms);
    for (int32_t i = 0; i < n; ++i) wy[i] = inv_sqrt_m[i] * kx[i];
    r.lambda = dot(r.y, wy);
    history.push_back(r.lambda);
    r.iterations = it + 1;
    double res2 = 0;
    for (int32_t i = 0; i < n; ++i) res2 += (wy[i] - r.lambda * r.y[i]).squaredNorm();
    r.residual = r.lambda > 0 ? std::sqrt(res2) / r.lambda : 0;
    if (it + 1 >= options.min_iterations && it >= window &&
        std::abs(r.lambda - history[it - window]) <= options.tolerance * r.lambda) {
      r.converged = true;
      break;
    }
    const double wn = std::sqrt(dot(wy, wy));
    if (!(wn > 0)) break;  // no stiffness on the free points
    for (int32_t i = 0; i < n; ++i) r.y[i] = wy[i] / wn;
  }
  r.lambda = std::max(r.lambda, 0.0);
  return r;
}

}  // namespace

double critical_step_for_mode(double omega2, double damping_rate) {
  if (!(omega2 > 0)) return std::numeric_limits<double>::infinity();
  // Root of omega^2 h^2 + 2 a h - 4 = 0, written without cancellation.
  return 4 / (damping_rate + std::sqrt(damping_rate * damping_rate + 4 * omega2));
}

double damped_critical_step(double omega, double spring_damping_time, double viscous_damping) {
  if (!(omega > 0)) return std::numeric_limits<double>::infinity();
  const double xi = (spring_damping_time * omega * omega + viscous_damping) / (2 * omega);
  return (2 / omega) * (std::sqrt(1 + xi * xi) - xi);
}

StabilityReport estimate_critical_step(const Model& model, const CriticalStepOptions& options) {
  const int32_t n = model.npoint();
  StabilityReport r;
  r.viscous_damping = model.viscous_damping;
  // c = d / k from the springs themselves and the shear element's tau (the
  // largest, to stay safe), so hand-built models with their own dampers are
  // covered too.
  r.spring_damping_time = damping_time(model);
  r.tool_contact_stiffness = options.tool_contact_stiffness;

  const RestStiffness k = rest_stiffness(model, options);
  std::vector<double> inv_sqrt_m(n, 0.0);
  for (int32_t i = 0; i < n; ++i) {
    if (model.inv_mass[i] > 0) {
      inv_sqrt_m[i] = std::sqrt(model.inv_mass[i]);
      ++r.free_points;
      if (k.tool_k[i] > 0) ++r.tool_points;
    }
  }

  // Gershgorin bound and its rows (core/stability/gershgorin.h).
  const GershgorinRows gershgorin = gershgorin_rows(model, options);
  const std::vector<double> rows = gershgorin_bounds(model, gershgorin, options);
  r.lambda_gershgorin = rows.empty() ? 0 : *std::max_element(rows.begin(), rows.end());

  // Candidate 1: the top mode of the full stiffness, with its own damping
  // (its spring part c y^T W_springs y plus the drag).
  const PowerResult top = power_iteration(model, k, inv_sqrt_m, kAll, options, r.lambda_gershgorin);
  r.iterations = top.iterations;
  r.converged = top.converged;
  r.residual = top.residual;
  r.lambda_max = top.lambda;
  r.omega_max = std::sqrt(r.lambda_max);
  const std::vector<Vec3>& y = top.y;
  std::vector<Vec3> x(n), kx(n);
  const auto rayleigh = [&](const std::vector<Vec3>& v, int terms) {
    for (int32_t i = 0; i < n; ++i) x[i] = inv_sqrt_m[i] * v[i];
    apply_stiffness(model, k, x, kx, terms);
    return dot(x, kx);
  };
  double damper_share = 0;  // y^T K_damper y / y^T K y of the shear element's damper
  if (r.lambda_max > 0) {
    const double s = rayleigh(y, kSprings), v = rayleigh(y, kVolume), t = rayleigh(y, kTool),
                 e = rayleigh(y, kShear), total = s + v + t + e;
    if (total > 0) {
      r.share_springs = s / total;
      r.share_volume = v / total;
      r.share_tool = t / total;
      r.share_shear = e / total;
      // The damper acts on the per-tet element at full k_t, whose energy in
      // this mode differs from the smoothed blend's.
      damper_share = model.has_smoothed_shear() ? rayleigh(y, kShearDamper) / total : r.share_shear;
    }
  }
  const double c = r.spring_damping_time, alpha = r.viscous_damping;
  // The dampers are D = c_s K_springs + tau K_shear (d = c_s k per spring,
  // the shear element's damper tau times its stiffness at rest), so the top
  // mode's damping rate is c_s s lambda + tau e lambda + alpha, with c_s the
  // springs' own damping time.
  const double c_springs = spring_damping_time(model), tau = model.shear_damping_time;
  const double top_rate = (c_springs * r.share_springs + tau * damper_share) * r.lambda_max + alpha;
  r.damping_ratio = r.omega_max > 0 ? top_rate / (2 * r.omega_max) : 0;
  r.dt_crit_undamped = r.omega_max > 0 ? 2 / r.omega_max : std::numeric_limits<double>::infinity();
  r.dt_crit = critical_step_for_mode(r.lambda_max, top_rate);
  // Candidate 2: the top mode of the damped part (springs, and the shear
  // element with its damper): the most damped stiff mode, whose damping may
  // shrink the step more than candidate 1's.
  // With a smoothed element the damped part (springs + the full per-tet
  // element) is not a part of K, so its top mode is always sought.
  const int damped = kSprings | (tau > 0 ? (model.has_smoothed_shear() ? kShearDamper : kShear) : 0);
  const double damped_share =
      model.has_smoothed_shear() && tau > 0 ? 0 : r.share_springs + (tau > 0 ? r.share_shear : 0);
  r.lambda_damped = r.lambda_max;
  if (c > 0 && damped_share < 0.999) {
    const PowerResult sp = power_iteration(model, k, inv_sqrt_m, damped, options, r.lambda_gershgorin);
    r.lambda_damped = sp.lambda;
    if (sp.lambda > 0) {
      const double omega2 = rayleigh(sp.y, kAll);
      r.dt_crit = std::min(r.dt_crit, critical_step_for_mode(omega2, c * sp.lambda + alpha));
    }
  }
  // Rigorous for exact eigenvalues: every mode has omega^2 <= lambda_max and
  // damping rate <= c lambda_damped + alpha (D <= c K_damped, both parts
  // positive semi-definite).
  r.dt_crit_bound = critical_step_for_mode(r.lambda_max, c * r.lambda_damped + alpha);
  r.dt_crit_gershgorin = guaranteed_critical_step(model, gershgorin, options);


  // Limiting points: the top mode's largest kinetic-energy shares m_i |x_i|^2 = |y_i|^2,
  // and the largest rows of the guaranteed bound.
  std::vector<double> share(n);
  for (int32_t i = 0; i < n; ++i) share[i] = y[i].squaredNorm();
  if (r.lambda_max > 0) r.label_shares = mode_share_by_label(model, share);
  auto point = [&](int32_t i) {
    LimitingPoint p;
    p.point = model.input_of_internal[i];
    p.position = model.rest_position[i];
    p.mode_share = r.lambda_max > 0 ? share[i] : 0;
    p.row_bound = rows[i];
    return p;
  };
  std::vector<uint8_t> limiting(n, 0);
  // Points with under 1 % of the largest share are not what limits the step.
  const double top_share = share.empty() ? 0 : *std::max_element(share.begin(), share.end());
  if (r.lambda_max > 0)
    for (int32_t i : largest(share, options.report_points)) {
      if (share[i] < 0.01 * top_share) break;
      r.mode_points.push_back(point(i));
      limiting[i] = 1;
    }
  for (int32_t i : largest(rows, options.report_points)) {
    if (rows[i] <= 0) break;
    r.gershgorin_points.push_back(point(i));
    limiting[i] = 1;
  }

  // Slivers: the worst-shaped tets touching a limiting point.
  std::vector<int32_t> tets;
  for (int32_t t = 0; t < model.ntet(); ++t) {
    const Tet& p = model.tet_points[t];
    if (limiting[p[0]] || limiting[p[1]] || limiting[p[2]] || limiting[p[3]]) tets.push_back(t);
  }
  std::vector<SliverTet> described;
  for (int32_t t : tets) described.push_back(describe_tet(model, t));
  std::sort(described.begin(), described.end(),
            [](const SliverTet& a, const SliverTet& b) { return a.quality < b.quality; });
  if (described.size() > static_cast<size_t>(options.report_tets)) described.resize(options.report_tets);
  r.slivers = std::move(described);
  return r;
}

std::vector<uint8_t> points_near_tool_path(const Model& model, const ToolSpec& tool) {
  // A capsule's segment reaches up to its extent from the path, in any orientation.
  const double reach = 2 * std::max(tool.radius, tool.mode == ToolMode::Pull ? tool.grasp_radius : 0.0) + tool.extent();
  std::vector<uint8_t> near(model.npoint(), 0);
  std::vector<double> path_distance(model.npoint());
  const auto& kf = tool.keyframes;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    const Vec3& x = model.rest_position[i];
    double d = kf.empty() ? std::numeric_limits<double>::infinity() : (x - kf[0].position).norm();
    for (size_t j = 1; j < kf.size(); ++j) {
      const Vec3 a = kf[j - 1].position, ab = kf[j].position - a;
      const double len2 = ab.squaredNorm();
      const double s = len2 > 0 ? std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      d = std::min(d, (x - (a + s * ab)).norm());
    }
    near[i] = d <= reach;
    path_distance[i] = d;
  }
  if (tool.mode == ToolMode::Push && tool.contact == ToolContact::Surface) {
    // Surface contact pushes every corner of a triangle the sphere reaches,
    // however far the corner: a triangle may come within reach when a
    // corner is within reach plus its longest edge (every point of it is
    // that close to each corner), and then all three corners may be touched.
    for (const Tri& t : model.surface) {
      double longest = 0, closest = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k) {
        longest = std::max(longest, (model.rest_position[t[(k + 1) % 3]] - model.rest_position[t[k]]).norm());
        closest = std::min(closest, path_distance[t[k]]);
      }
      if (closest <= reach + longest)
        for (int32_t p : t) near[p] = 1;
    }
  }
  return near;
}

CriticalStepOptions critical_step_options(const Model& model, const ToolSpec* tool) {
  CriticalStepOptions o;
  if (tool) {
    // A grasper's two jaws and friction's stick spring stiffen a point beyond one penalty share.
    o.tool_contact_stiffness = tool->contact_stiffness * tool->backend_tool().stiffness_factor();
    o.tool_may_touch = points_near_tool_path(model, *tool);
  }
  return o;
}

StepSuggestion suggest_step(const StabilityReport& report, double tick, double safety) {
  StepSuggestion s;
  s.tick = tick;
  const double limit = safety * report.dt_crit;
  // Clamped before the cast: an extreme stiffness can ask for more substeps
  // than an int holds (found by the scenario fuzz harness).
  s.substeps = std::isfinite(limit) && limit > 0
                   ? std::max<int32_t>(1, static_cast<int32_t>(std::min(std::ceil(tick / limit), 2147483647.0)))
                   : 1;
  s.dt = tick / s.substeps;
  return s;
}

}  // namespace organsim
