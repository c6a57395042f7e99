#include "core/run/integrator_report.h"

#include <algorithm>
#include <vector>

#include "core/util/format.h"

namespace organsim {

namespace {
double share(int64_t steps, const IntegratorStats& s) {
  return s.steps() > 0 ? static_cast<double>(steps) / static_cast<double>(s.steps()) : 0.0;
}
}  // namespace

nlohmann::json integrator_meta(const Backend& backend) {
  nlohmann::json j = {{"name", integrator_name(backend.step_plan().integrator)}};
  const IntegratorStats* s = backend.integrator_stats();
  if (!s) return j;
  std::vector<int32_t> it = s->cg_iterations;
  int32_t median = 0, max = 0;
  if (!it.empty()) {
    std::nth_element(it.begin(), it.begin() + static_cast<std::ptrdiff_t>(it.size() / 2), it.end());
    median = it[it.size() / 2];
    max = *std::max_element(it.begin(), it.end());
  }
  j["steps"] = s->steps();
  j["cg_iterations_median"] = median;
  j["cg_iterations_max"] = max;
  j["cg_max_iterations"] = s->cg_max_iterations;
  j["cg_residual_max"] = s->max_residual;
  j["cg_unconverged_steps"] = s->unconverged_steps;
  j["cg_unconverged_share"] = share(s->unconverged_steps, *s);
  j["alternating_steps"] = s->alternating_steps;
  j["alternating_share"] = share(s->alternating_steps, *s);
  return j;
}

std::string integrator_warning(const Backend& backend) {
  const IntegratorStats* s = backend.integrator_stats();
  if (!s || s->steps() == 0) return "";
  std::string warning;
  const double unconverged = share(s->unconverged_steps, *s), alternating = share(s->alternating_steps, *s);
  if (unconverged > kUnconvergedShareWarning)
    warning = "implicit Euler: the conjugate gradients stopped at cg_max_iterations = " +
              std::to_string(s->cg_max_iterations) + " above cg_tolerance in " + std::to_string(s->unconverged_steps) +
              " of " + std::to_string(s->steps()) + " steps (" + format_number(100 * unconverged, "%.3g") +
              " %; largest final residual " + format_number(s->max_residual) +
              "): raise time.cg_max_iterations, loosen time.cg_tolerance or try time.preconditioner \"two_level\"";
  if (alternating > kUnconvergedShareWarning)
    warning += std::string(warning.empty() ? "" : "; ") + "implicit Euler: the state swung back and forth between two in " +
               std::to_string(s->alternating_steps) + " of " + std::to_string(s->steps()) + " steps (" +
               format_number(100 * alternating, "%.3g") +
               " %: each step's velocity change undoing the last, as when one linearisation per step overshoots a stiff "
               "contact; the forces logged are not the implicit step's): raise time.newton_iterations (4 or more) or "
               "use a smaller time.dt";
  return warning;
}

std::string integrator_summary(const nlohmann::json& meta) {
  if (!meta.is_object() || !meta.contains("cg_iterations_median")) return "";
  return "CG iterations per step median " + std::to_string(meta["cg_iterations_median"].get<int>()) + ", max " +
         std::to_string(meta["cg_iterations_max"].get<int>()) + "; largest final residual " +
         format_number(meta["cg_residual_max"].get<double>()) + "; " +
         std::to_string(meta["cg_unconverged_steps"].get<int64_t>()) + " steps stopped at cg_max_iterations; " +
         std::to_string(meta.value("alternating_steps", int64_t{0})) + " alternating";
}

std::string integrator_progress(const Backend& backend) {
  const IntegratorStats* s = backend.integrator_stats();
  if (!s) return "";
  std::string out;
  if (s->unconverged_steps > 0)
    out = "CG at its limit in " + std::to_string(s->unconverged_steps) + " of " + std::to_string(s->steps()) + " steps";
  if (s->alternating_steps > 0)
    out += (out.empty() ? "" : ", ") + std::string("alternating in ") + std::to_string(s->alternating_steps) + " of " +
           std::to_string(s->steps()) + " steps";
  return out;
}

}  // namespace organsim
