#include "core/stability/blowup_monitor.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/mesh/tet_mesh.h"
#include "core/model/nodal_volume.h"
#include "core/model/shear_element.h"
#include "core/physics/force_law.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {

std::string kind_name(BlowupFinding::Kind k) {
  switch (k) {
    case BlowupFinding::Kind::NonFinite: return "non-finite position";
    case BlowupFinding::Kind::Energy: return "kinetic energy growing with no work input";
    case BlowupFinding::Kind::Strain: return "spring strain beyond the bound";
    case BlowupFinding::Kind::Inversion: return "inverted tet";
  }
  return "";
}

// (L - r) / r > bound, i.e. L^2 > (1 + bound)^2 r^2, for some tissue spring
// of [begin, end) (a suture is a thread, not tissue: its length says
// nothing of stability).
bool any_spring_beyond(const Model& model, const std::vector<Vec3>& x, double bound, int32_t begin, int32_t end) {
  const double c = (1 + bound) * (1 + bound);
  int found = 0;
  for (int32_t s = begin; s < end; ++s) {
    const auto [a, b] = model.spring_ends[s];
    const double r = model.spring_rest[s];
    found |= (x[b] - x[a]).squaredNorm() > c * r * r;
  }
  return found != 0;
}

// V < -bound V_r for some tet of [begin, end) (rest volumes are positive).
bool any_tet_beyond(const Model& model, const std::vector<Vec3>& x, double bound, int32_t begin, int32_t end) {
  int found = 0;
  for (int32_t t = begin; t < end; ++t) {
    const Tet& p = model.tet_points[t];
    found |= signed_volume(x[p[0]], x[p[1]], x[p[2]], x[p[3]]) < -bound * model.tet_rest_volume[t];
  }
  return found != 0;
}

// Check 1: the first non-finite position.
std::optional<BlowupFinding> check_finite(const Model& model, const std::vector<Vec3>& x) {
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if (!x[i].allFinite()) {
      BlowupFinding f;
      f.kind = BlowupFinding::Kind::NonFinite;
      f.point = model.input_of_internal[i];
      f.detail = "position is not finite";
      return f;
    }
  }
  return std::nullopt;
}

// Checks 3 and 4 on share `share` of `shares` of the springs and tets: whether
// any is beyond its bound; `items`: how many were looked at.
bool share_beyond(const Model& model, const std::vector<Vec3>& x, const BlowupMonitorOptions& options, int32_t share,
                  int32_t shares, int64_t& items) {
  const auto part = [&](int32_t n, int32_t k) { return static_cast<int32_t>(static_cast<int64_t>(n) * k / shares); };
  const int32_t s0 = part(model.first_suture(), share), s1 = part(model.first_suture(), share + 1);
  const int32_t t0 = part(model.ntet(), share), t1 = part(model.ntet(), share + 1);
  items = (s1 - s0) + (options.check_inversion ? t1 - t0 : 0);
  return any_spring_beyond(model, x, options.max_strain, s0, s1) ||
         (options.check_inversion && any_tet_beyond(model, x, options.max_inversion, t0, t1));
}

}  // namespace

double elastic_energy(const Model& model, const std::vector<Vec3>& x) {
  double e = 0;
  for (int32_t s = 0; s < model.nspring(); ++s) {
    const auto [a, b] = model.spring_ends[s];
    e += force_law::spring_energy(model.spring_k[s], (x[b] - x[a]).norm(), model.spring_rest[s]);
  }
  if (model.has_nodal_volume()) {
    std::vector<double> v;
    nodal_volumes(model, x, v);
    for (int32_t a = 0; a < model.npoint(); ++a)
      e += force_law::volume_energy(model.point_volume_k[a], v[a], model.point_rest_volume[a]);
  } else if (model.has_volume()) {
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const Tet& p = model.tet_points[t];
      e += force_law::volume_energy(model.tet_k[t], signed_volume(x[p[0]], x[p[1]], x[p[2]], x[p[3]]),
                                    model.tet_rest_volume[t]);
    }
  }
  return e + shear_element_energy(model, x);
}

std::optional<BlowupFinding> check_geometry(const Model& model, const std::vector<Vec3>& x,
                                            const BlowupMonitorOptions& options) {
  if (auto f = check_finite(model, x)) return f;
  // The worst spring, if any is beyond the bound. A quick pass first, on
  // squared lengths (no square root or division): a check that finds
  // nothing, the usual case, then costs a few percent of the steps between
  // checks (organsim bench). One thread on purpose: on a loaded machine a
  // parallel region here costs far more than it saves.
  int32_t worst = -1;
  double worst_strain = options.max_strain;
  if (any_spring_beyond(model, x, options.max_strain, 0, model.first_suture())) {
    for (int32_t s = 0; s < model.first_suture(); ++s) {
      const auto [a, b] = model.spring_ends[s];
      const double strain = ((x[b] - x[a]).norm() - model.spring_rest[s]) / model.spring_rest[s];
      if (strain > worst_strain) {
        worst_strain = strain;
        worst = s;
      }
    }
  }
  if (worst >= 0) {
    const auto [a, b] = model.spring_ends[worst];
    BlowupFinding f;
    f.kind = BlowupFinding::Kind::Strain;
    // Name the end that moved more.
    const bool a_moved_more =
        (x[a] - model.rest_position[a]).squaredNorm() >= (x[b] - model.rest_position[b]).squaredNorm();
    f.point = model.input_of_internal[a_moved_more ? a : b];
    f.value = worst_strain;
    f.detail = "spring " + std::to_string(model.input_of_internal[a]) + "-" +
               std::to_string(model.input_of_internal[b]) + " stretched by " +
               format_number(100 * worst_strain, "%.0f") + " % (bound " +
               format_number(100 * options.max_strain, "%.0f") + " %)";
    return f;
  }
  if (options.check_inversion && any_tet_beyond(model, x, options.max_inversion, 0, model.ntet())) {
    int32_t worst_tet = -1;
    double worst_ratio = 0;  // V / V_r, the most negative
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const Tet& p = model.tet_points[t];
      const double ratio = signed_volume(x[p[0]], x[p[1]], x[p[2]], x[p[3]]) / model.tet_rest_volume[t];
      if (ratio < -options.max_inversion && (worst_tet < 0 || ratio < worst_ratio)) {
        worst_tet = t;
        worst_ratio = ratio;
      }
    }
    if (worst_tet >= 0) {
      const Tet& p = model.tet_points[worst_tet];
      int32_t moved = p[0];
      for (int32_t q : p)
        if ((x[q] - model.rest_position[q]).squaredNorm() > (x[moved] - model.rest_position[moved]).squaredNorm()) moved = q;
      BlowupFinding f;
      f.kind = BlowupFinding::Kind::Inversion;
      f.point = model.input_of_internal[moved];
      f.value = worst_ratio * model.tet_rest_volume[worst_tet];
      f.detail = "tet (" + std::to_string(model.input_of_internal[p[0]]) + ", " +
                 std::to_string(model.input_of_internal[p[1]]) + ", " + std::to_string(model.input_of_internal[p[2]]) +
                 ", " + std::to_string(model.input_of_internal[p[3]]) + ") inverted: volume " +
                 format_number(worst_ratio, "%.3g") + " x its rest volume";
      return f;
    }
  }
  return std::nullopt;
}

BlowupMonitor::BlowupMonitor(BlowupMonitorOptions options, BlowupContext context)
    : options_(options), context_(std::move(context)) {
  if (options_.interval_ticks < 1)
    throw Error(ErrorKind::Usage, "blow-up check interval must be >= 1 tick, got " +
                                      std::to_string(options_.interval_ticks));
}

void BlowupMonitor::on_start(const Model& model, Backend& backend) {
  backend.positions(x_start_);
  x_prev_ = x_start_;
  x_ = x_start_;
  elastic_start_ = elastic_energy(model, x_start_);
  tool_work_ = 0;
  last_check_t_ = last_tick_t_ = backend.time();
  checks_ = 0;
  scan_share_ = -1;
  // Floor: KE of the whole mass moving at 1e-3 of the model's size per second.
  Vec3 lo = x_start_.empty() ? Vec3::Zero() : x_start_[0], hi = lo;
  for (const Vec3& p : x_start_) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double v = 1e-3 * (hi - lo).norm();
  energy_floor_ = 0.5 * model.total_mass() * v * v;
}

void BlowupMonitor::on_topology_changed(const Model& next, Backend& /*backend*/) {
  for (auto* x : {&x_start_, &x_prev_, &x_}) {
    const size_t old = x->size();
    x->resize(static_cast<size_t>(next.npoint()));
    for (size_t i = old; i < x->size(); ++i) (*x)[i] = (*x)[static_cast<size_t>(next.origin[i])];
  }
}

std::optional<BlowupFinding> BlowupMonitor::check_energy(const Model& model, double seconds) const {
  if (!(seconds > 0)) return std::nullopt;
  double ke = 0, gravity_work = 0, top = 0;
  int32_t top_point = -1;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if (model.fixed[i]) continue;
    const Vec3 v = (x_[i] - x_prev_[i]) / seconds;
    const double e = 0.5 * model.mass[i] * v.squaredNorm();
    ke += e;
    if (e > top) {
      top = e;
      top_point = i;
    }
    gravity_work += model.mass[i] * model.gravity.dot(x_[i] - x_start_[i]);
  }
  const double budget = elastic_start_ + std::max(gravity_work, 0.0) + tool_work_;
  if (ke <= options_.energy_factor * budget + energy_floor_) return std::nullopt;
  BlowupFinding f;
  f.kind = BlowupFinding::Kind::Energy;
  f.point = top_point >= 0 ? model.input_of_internal[top_point] : -1;
  f.value = ke;
  f.detail = "kinetic energy " + format_number(ke) + " J exceeds what gravity and the tool put in (" +
             format_number(budget) + " J, plus the initial elastic energy); the fastest point carries " +
             format_number(100 * top / ke, "%.0f") + " %";
  return f;
}

void BlowupMonitor::on_tick(const Model& model, Backend& backend, const TickInfo& info) {
  // Tool work bound, every tick (cheap, no readback): |F| |dc| over the
  // tick's own path, the first tick's included (a grasp that pulls from the
  // first tick on puts energy in at once).
  if (info.tool_active) tool_work_ += info.reaction.force.norm() * (info.tool_center - info.tool_from).norm();
  const int32_t behind = options_.reaction_positions ? backend.reaction_latency_ticks() : 0;
  const double tick_length = info.t - last_tick_t_;
  last_tick_t_ = info.t;
  // Before the reaction's tick exists (the first `behind` ticks) there is nothing new to check.
  if ((info.tick + 1) % options_.interval_ticks == 0 && info.tick >= behind) {
    std::swap(x_prev_, x_);
    if (options_.reaction_positions) backend.reaction_positions(x_);
    else backend.positions(x_);
    ++checks_;
    const double t_x = info.t - behind * tick_length;  // the end of the tick x_ is of
    // A growing mode shows as energy first; report that as the cause when it holds.
    std::optional<BlowupFinding> finding = check_finite(model, x_);
    if (!finding) finding = check_energy(model, t_x - last_check_t_);
    last_check_t_ = t_x;
    if (finding) throw Error(ErrorKind::Numerical, describe(model, *finding, info.t, info));
    scan_share_ = 0;
  }
  if (scan_share_ < 0) return;
  int64_t items = 0;
  const bool beyond = share_beyond(model, x_, options_, scan_share_, options_.interval_ticks, items);
  largest_tick_scan_ = std::max(largest_tick_scan_, items);
  if (++scan_share_ == options_.interval_ticks) scan_share_ = -1;
  // The whole pass names the worst spring or tet (a finding is rare: its cost does not matter).
  if (beyond)
    if (auto finding = check_geometry(model, x_, options_))
      throw Error(ErrorKind::Numerical, describe(model, *finding, info.t, info));
}

std::string BlowupMonitor::describe(const Model& model, const BlowupFinding& f, double t, const TickInfo& info) const {
  std::string msg = "run stopped at t = " + format_number(t, "%.6g") + " s: " + kind_name(f.kind) + " at point " +
                    std::to_string(f.point) + " (input numbering): " + f.detail + ". Likely cause: ";
  const auto& st = context_.stability;
  const int32_t internal = f.point >= 0 ? model.internal_of_input[f.point] : -1;
  bool near_tool = false;
  if (internal >= 0 && info.tool_active && context_.tool_radius > 0 && x_.size() == model.rest_position.size() &&
      x_[internal].allFinite())
    near_tool = (x_[internal] - info.tool_center).norm() < 2 * context_.tool_radius;
  bool limiting = false;
  if (st)
    for (const auto& p : st->mode_points) limiting |= p.point == f.point;
  const bool verlet = context_.integrator == Integrator::Verlet;
  const bool damping_only = context_.integrator == Integrator::ImplicitDamping;
  if (st && verlet && context_.dt > st->dt_crit) {
    msg += "time.dt = " + format_number(context_.dt) + " s exceeds dt_crit = " + format_number(st->dt_crit) +
           " s, so the stiffest mode grows every step; use a smaller dt or more substeps.";
  } else if (st && damping_only && context_.dt > st->dt_crit_undamped) {
    msg += "time.dt = " + format_number(context_.dt) +
           " s exceeds the undamped limit 2/omega_max = " + format_number(st->dt_crit_undamped) +
           " s that implicit_damping needs, so the stiffest mode grows every step; use "
           "a smaller dt or \"integrator\": \"implicit_euler\".";
  } else if (near_tool && f.kind == BlowupFinding::Kind::Inversion) {
    msg += "the tool pushed the material through itself (penetration deeper than the tets can resist); move the "
           "tool less deep or slower, or raise material.volume_modulus.";
  } else if (near_tool) {
    msg += "stiff or fast tool contact (tool.contact_stiffness = " + format_number(context_.tool_contact_stiffness) +
           " N/m) near this point; lower it, slow the tool, or use a smaller dt.";
  } else if (limiting) {
    msg += "this point limits the critical step (stiff springs or slivers around it, see --plan); use a smaller "
           "dt or remesh.";
  } else if (f.kind == BlowupFinding::Kind::Inversion || f.kind == BlowupFinding::Kind::Strain) {
    msg += "a deformation beyond what linear springs represent (they are realistic below about 10 % strain); "
           "reduce the load, or raise material.volume_modulus.";
  } else {
    msg += "a numerically unstable step";
    if (st) msg += " (dt_crit = " + format_number(st->dt_crit) + " s at rest; deformation can lower it)";
    msg += "; use a smaller dt.";
  }
  return msg;
}

double measure_check_ms(const Model& model, Backend& backend, int repeats) {
  BlowupMonitor monitor({}, {});
  monitor.on_start(model, backend);
  std::vector<double> ms;
  TickInfo info;
  for (int i = 0; i < std::max(repeats, 1); ++i) {
    info.tick = i;
    info.t = backend.time() + (i + 1) * 1e-3;  // positions do not move: no finding
    const auto start = std::chrono::steady_clock::now();
    monitor.on_tick(model, backend, info);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  std::nth_element(ms.begin(), ms.begin() + ms.size() / 2, ms.end());
  return ms[ms.size() / 2];
}

}  // namespace organsim
