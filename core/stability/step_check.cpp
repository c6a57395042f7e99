// The pre-run step check and how a StabilityReport is shown (text, JSON).
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/stability/critical_step.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {

std::string point_list(const std::vector<LimitingPoint>& points, size_t count) {
  std::string s;
  for (size_t i = 0; i < std::min(count, points.size()); ++i) s += (i ? ", " : "") + std::to_string(points[i].point);
  return s;
}

// What dominates the top mode, in words.
std::string dominant_term(const StabilityReport& r) {
  if (r.share_volume >= r.share_springs && r.share_volume >= r.share_tool && r.share_volume >= r.share_shear)
    return "volume term (slivers raise it: K |dV/dx|^2 / V)";
  if (r.share_shear >= r.share_springs && r.share_shear >= r.share_tool)
    return "shear element (slivers raise it: mu_e V |g|^2)";
  if (r.share_tool >= r.share_springs) return "tool contact stiffness";
  return "springs";
}

nlohmann::json point_json(const LimitingPoint& p) {
  return {{"point", p.point},
          {"position", {p.position.x(), p.position.y(), p.position.z()}},
          {"mode_share", p.mode_share},
          {"row_bound", p.row_bound}};
}

}  // namespace

std::string check_time_step(const StabilityReport& report, double dt, int32_t substeps, bool allow_unstable,
                            Integrator integrator) {
  if (integrator == Integrator::ImplicitEuler) return {};
  if (integrator == Integrator::ImplicitDamping) {
    // Only the dampers are implicit: the elastic forces' symplectic Euler
    // needs dt below the undamped limit.
    if (!(dt > report.dt_crit_undamped)) return {};
    const std::string msg = "time.dt = " + format_number(dt) +
                            " s exceeds the undamped limit 2/omega_max = " + format_number(report.dt_crit_undamped) +
                            " s that implicit_damping needs (its elastic forces are "
                            "explicit); use a smaller dt or \"integrator\": \"implicit_euler\"";
    if (!allow_unstable) throw Error(ErrorKind::Numerical, msg + ", or pass --allow-unstable to run anyway");
    return "warning: " + msg + ". Running anyway (--allow-unstable).";
  }
  if (!(dt > report.dt_crit)) return {};
  const StepSuggestion s = suggest_step(report, dt * substeps);
  std::string msg = "time.dt = " + format_number(dt) +
                    " s exceeds the critical step dt_crit = " + format_number(report.dt_crit) +
                    " s of this model (limited by the " + dominant_term(report) + " at points " +
                    point_list(report.mode_points, 3) + ", input numbering); use time.dt = " + format_number(s.dt) +
                    " s with time.substeps = " + std::to_string(s.substeps) + " to keep the haptic tick of " +
                    format_number(s.tick) + " s";
  if (!allow_unstable) throw Error(ErrorKind::Numerical, msg + ", or pass --allow-unstable to run anyway");
  return "warning: " + msg +
         ". Running anyway (--allow-unstable): expect the top mode to grow every step until the blow-up "
         "check stops the run.";
}

nlohmann::json to_json(const StabilityReport& r) {
  nlohmann::json j;
  j["dt_crit"] = r.dt_crit;
  j["dt_crit_undamped"] = r.dt_crit_undamped;
  j["dt_crit_bound"] = r.dt_crit_bound;
  j["dt_crit_gershgorin"] = r.dt_crit_gershgorin;
  j["lambda_damped"] = r.lambda_damped;
  j["omega_max"] = r.omega_max;
  j["lambda_max"] = r.lambda_max;
  j["lambda_gershgorin"] = r.lambda_gershgorin;
  j["damping_ratio"] = r.damping_ratio;
  j["spring_damping_time"] = r.spring_damping_time;
  j["viscous_damping"] = r.viscous_damping;
  j["tool_contact_stiffness"] = r.tool_contact_stiffness;
  j["tool_points"] = r.tool_points;
  j["free_points"] = r.free_points;
  j["power_iterations"] = r.iterations;
  j["converged"] = r.converged;
  j["residual"] = r.residual;
  j["mode_share"] = {{"springs", r.share_springs},
                     {"volume", r.share_volume},
                     {"shear_element", r.share_shear},
                     {"tool", r.share_tool}};
  j["limiting_points"] = nlohmann::json::array();
  for (const auto& p : r.mode_points) j["limiting_points"].push_back(point_json(p));
  j["gershgorin_points"] = nlohmann::json::array();
  for (const auto& p : r.gershgorin_points) j["gershgorin_points"].push_back(point_json(p));
  if (!r.label_shares.empty()) {
    j["label_shares"] = nlohmann::json::array();
    for (const auto& l : r.label_shares) j["label_shares"].push_back({{"label", l.label}, {"share", l.share}});
  }
  j["slivers"] = nlohmann::json::array();
  for (const auto& s : r.slivers)
    j["slivers"].push_back({{"points", s.points},
                            {"volume", s.volume},
                            {"quality", s.quality},
                            {"min_dihedral_deg", s.min_dihedral_deg}});
  return j;
}

std::string format_stability_report(const StabilityReport& r, double dt, int32_t substeps, Integrator integrator) {
  std::ostringstream o;
  o << "stability (at rest):\n";
  o << "  dt_crit " << format_number(r.dt_crit) << " s (undamped 2/omega_max " << format_number(r.dt_crit_undamped)
    << " s, damping ratio of the top mode " << format_number(r.damping_ratio, "%.3g") << ")\n"
    << "  bounds: all modes at once " << format_number(r.dt_crit_bound) << " s, guaranteed "
    << format_number(r.dt_crit_gershgorin) << " s\n";
  o << "  omega_max " << format_number(r.omega_max) << " rad/s from " << r.iterations << " power iterations"
    << (r.converged ? "" : " (NOT converged)") << "; top mode: springs " << format_number(100 * r.share_springs, "%.0f")
    << " %, volume " << format_number(100 * r.share_volume, "%.0f")
    << (r.share_shear > 0 ? " %, shear element " + format_number(100 * r.share_shear, "%.0f") : std::string())
    << " %, tool " << format_number(100 * r.share_tool, "%.0f") << " %\n";
  if (r.tool_points > 0)
    o << "  tool contact " << format_number(r.tool_contact_stiffness) << " N/m counted on " << r.tool_points
      << " points near the tool path\n";
  o << "  limiting points (input numbering): " << point_list(r.mode_points, r.mode_points.size())
    << "; largest bound rows: " << point_list(r.gershgorin_points, r.gershgorin_points.size()) << "\n";
  if (!r.label_shares.empty()) {
    o << "  limited by label " << r.label_shares[0].label << "'s cells: top mode by label";
    for (const auto& l : r.label_shares) o << " " << l.label << " " << format_number(100 * l.share, "%.0f") << " %";
    o << "\n";
  }
  for (const auto& s : r.slivers)
    o << "  tet (" << s.points[0] << ", " << s.points[1] << ", " << s.points[2] << ", " << s.points[3] << "): quality "
      << format_number(s.quality, "%.3f") << ", min dihedral " << format_number(s.min_dihedral_deg, "%.1f")
      << " deg, volume " << format_number(s.volume) << " m^3\n";
  if (integrator == Integrator::ImplicitDamping) {
    o << "  dt " << format_number(dt) << " s is " << format_number(dt / r.dt_crit_undamped, "%.2f")
      << " x the undamped 2/omega_max that implicit damping needs (" << format_number(dt / r.dt_crit, "%.3g")
      << " x dt_crit): " << (dt > r.dt_crit_undamped ? "UNSTABLE, refused without --allow-unstable" : "stable") << "\n";
    return o.str();
  }
  if (integrator == Integrator::ImplicitEuler) {
    o << "  dt " << format_number(dt) << " s spans " << format_number(dt / r.dt_crit, "%.3g")
      << " x dt_crit: implicit Euler, not bounded by dt_crit (it damps the modes above 1/dt instead: "
         "docs/integrators.md)\n";
    return o.str();
  }
  const StepSuggestion s = suggest_step(r, dt * substeps);
  o << "  dt " << format_number(dt) << " s is " << format_number(dt / r.dt_crit, "%.2f")
    << " x dt_crit: " << (dt > r.dt_crit ? "UNSTABLE, refused without --allow-unstable" : "stable") << "; suggested dt "
    << format_number(s.dt) << " s x " << s.substeps << " substeps for the tick of " << format_number(s.tick) << " s\n";
  return o.str();
}

}  // namespace organsim
