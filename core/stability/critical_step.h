#pragma once
// The critical time step of a Model at rest, before a run (docs/stability.md).
//
// Position Verlet is central differences: undamped it is stable while
// dt < 2 / omega_max, omega_max^2 = largest eigenvalue of M^-1 K with K the
// stiffness at rest (springs k u u^T, volume k_v g_i g_j^T, shear element
// k_t ((g_i . g_j) I + g_j g_i^T), tool contact).
// We estimate omega_max^2 by power iteration on the symmetric form
// W = M^-1/2 K M^-1/2 over the free points and bound it from above by
// a block-diagonal majorant (gershgorin.h). Damping then shrinks the step (see damped_critical_step).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/model/model.h"
#include "core/sim/step_plan.h"
#include "core/scenario/tool_spec.h"

namespace organsim {

struct CriticalStepOptions {
  // Tool contact adds at most k_c (push penalty along the normal, pull
  // attachment springs isotropically) to the diagonal block of each point it
  // touches (surface contact: the sum over a point's triangles of w_i^2 k_t,
  // which force_law::triangle_penalty_scale keeps within k_c s_i). We add
  // k_c I to every point that *may* be touched: an upper bound on K, so
  // dt_crit stays on the safe side.
  double tool_contact_stiffness = 0;      // N/m; 0 = no tool term
  std::vector<uint8_t> tool_may_touch;    // internal numbering (npoint); empty = every free point
  int32_t max_iterations = 3000;
  int32_t min_iterations = 50;
  // Converged when the Rayleigh quotient changed by less than this (relative)
  // over the last 20 iterations.
  double tolerance = 1e-5;
  int32_t report_points = 5;  // limiting points listed
  int32_t report_tets = 5;    // slivers listed
};

// A point that limits the step, in the user's (input) numbering.
struct LimitingPoint {
  int32_t point = -1;      // input numbering
  Vec3 position{0, 0, 0};  // rest position, m
  double mode_share = 0;   // share of the top mode's kinetic energy m_i |x_i|^2 (0..1)
  double row_bound = 0;    // row of the guaranteed bound on M^-1 K at this point, 1/s^2
};

// How much of the top mode lies on one label's cells (labelled meshes).
struct LabelModeShare {
  int32_t label = 0;
  double share = 0;  // of the top mode's kinetic energy, 0..1; the labels' shares sum to 1
};

// A badly shaped tet at a limiting point.
struct SliverTet {
  std::array<int32_t, 4> points{};  // input numbering
  double volume = 0;                // rest volume, m^3
  double quality = 0;               // 6 sqrt(2) V / l_max^3: 1 regular, -> 0 flat
  double min_dihedral_deg = 0;      // smallest dihedral angle, degrees
};

struct StabilityReport {
  int32_t free_points = 0;
  double lambda_max = 0;          // estimated largest eigenvalue of M^-1 K, 1/s^2
  double lambda_gershgorin = 0;   // guaranteed upper bound on it (core/stability/gershgorin.h), 1/s^2
  double omega_max = 0;           // sqrt(lambda_max), rad/s
  int32_t iterations = 0;         // power iterations done
  bool converged = false;
  double residual = 0;            // |W y - lambda y| / lambda for the final unit y
  // Shares of the top mode's stiffness y^T W y from each term (sum 1).
  double share_springs = 0, share_volume = 0, share_tool = 0, share_shear = 0;  // shear: the shear element

  // Largest eigenvalue of M^-1 K_damped, the damped part: the springs, and
  // the shear element when it has its damper, 1/s^2.
  double lambda_damped = 0;
  // Damping of the top mode: xi = ((c_s s + tau e) omega^2 + alpha) / (2 omega),
  // with c_s the springs' damping time (d = c_s k), s their share of the
  // mode, tau and e the shear element's damping time and share, alpha the drag.
  double spring_damping_time = 0;  // the largest of c_s and tau, s
  double viscous_damping = 0;      // 1/s
  double tool_contact_stiffness = 0;  // N/m, as included
  int32_t tool_points = 0;         // points the tool term was applied to
  double damping_ratio = 0;        // xi

  double dt_crit_undamped = 0;     // 2 / omega_max, s
  // With damping: the step `run` enforces, s. The smaller of two candidate
  // modes' limits: the top mode of K with its own damping, and the top mode
  // of the springs (the damped part) with its frequency under the full K.
  double dt_crit = 0;
  double dt_crit_bound = 0;        // every mode at once: omega^2 = lambda_max, rate c lambda_damped + alpha, s
  double dt_crit_gershgorin = 0;   // the same from the guaranteed bound: a guaranteed-stable step, s

  std::vector<LimitingPoint> mode_points;        // largest components of the top mode
  std::vector<LimitingPoint> gershgorin_points;  // largest rows of the guaranteed bound
  std::vector<SliverTet> slivers;                // worst tets at those points
  // Labelled meshes: the top mode's kinetic energy per label, largest first
  // (the first label's cells limit dt_crit); a point on an interface splits
  // its share by the mass each label's tets give it. Empty without labels.
  std::vector<LabelModeShare> label_shares;
};

// Estimates dt_crit of `model` at rest. Deterministic (fixed start vector).
StabilityReport estimate_critical_step(const Model& model, const CriticalStepOptions& options = {});

// Largest stable step of position Verlet with a backward-difference damper
// (as the backends integrate it) for a mode of frequency omega (rad/s):
//   x+ = x + (1 - a h)(x - x-) - h^2 w^2 x - h c w^2 (x - x-)
// is stable iff h^2 w^2 + 2 h (c w^2 + a) < 4, i.e.
//   h < (2 / w) (sqrt(1 + xi^2) - xi),  xi = (c w^2 + a) / (2 w).
// The same bound holds for the whole model when every mode's damping is at
// most c w^2 + a (spring dampers d = c k and the shear element's damper
// are c times part of K).
double damped_critical_step(double omega, double spring_damping_time, double viscous_damping);

// The general form: a mode with omega^2 (1/s^2) and damping rate a = y^T M^-1 D y
// (1/s; D the dampers, plus the drag alpha) is stable iff omega^2 h^2 + 2 a h < 4.
double critical_step_for_mode(double omega2, double damping_rate);

// Points whose rest position lies within reach of the tool's path (keyframe
// polyline), internal numbering: radius (or grasp radius for pull) plus one
// more radius of margin for the material the tool drags along, plus a
// capsule's extent (ToolSpec::extent, any orientation); with surface
// contact also every corner of a surface triangle that may come that close.
std::vector<uint8_t> points_near_tool_path(const Model& model, const ToolSpec& tool);

// Options for a scene: the tool's contact stiffness on the points near its
// path (no tool term when `tool` is null).
CriticalStepOptions critical_step_options(const Model& model, const ToolSpec* tool);

// A stable step that keeps the haptic tick: substeps' = ceil(tick / (safety dt_crit)),
// dt' = tick / substeps'.
struct StepSuggestion {
  double dt = 0;          // s
  int32_t substeps = 0;
  double tick = 0;        // s, = dt * substeps
};
StepSuggestion suggest_step(const StabilityReport& report, double tick, double safety = 0.9);

// Before a run: throws Error(Numerical) when dt > report.dt_crit, giving
// dt_crit, the limiting points and the suggested dt and substeps. With
// allow_unstable it returns the warning text instead (empty when dt is fine).
// With implicit Euler (unconditionally stable for the linear part) no dt is
// refused: returns "".
std::string check_time_step(const StabilityReport& report, double dt, int32_t substeps, bool allow_unstable,
                            Integrator integrator = Integrator::Verlet);

// For the force log's meta ("stability") and the study.
nlohmann::json to_json(const StabilityReport& report);
// Multi-line text for `run --plan`.
// With implicit Euler its last line says how many dt_crit the step spans.
std::string format_stability_report(const StabilityReport& report, double dt, int32_t substeps,
                                    Integrator integrator = Integrator::Verlet);

}  // namespace organsim
