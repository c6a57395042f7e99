#include "core/run/integrator_report.h"

#include <algorithm>
#include <vector>

#include "core/util/format.h"

namespace organsim {

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
  j["cg_unconverged_share"] = s->steps() > 0 ? static_cast<double>(s->unconverged_steps) / static_cast<double>(s->steps()) : 0.0;
  return j;
}

std::string integrator_warning(const Backend& backend) {
  const IntegratorStats* s = backend.integrator_stats();
  if (!s || s->steps() == 0) return "";
  const double share = static_cast<double>(s->unconverged_steps) / static_cast<double>(s->steps());
  if (!(share > kUnconvergedShareWarning)) return "";
  return "implicit Euler: the conjugate gradients stopped at cg_max_iterations = " +
         std::to_string(s->cg_max_iterations) + " above cg_tolerance in " + std::to_string(s->unconverged_steps) +
         " of " + std::to_string(s->steps()) + " steps (" + format_number(100 * share, "%.3g") +
         " %; largest final residual " + format_number(s->max_residual) +
         "): raise time.cg_max_iterations, loosen time.cg_tolerance or try time.preconditioner \"rest_cholesky\"";
}

std::string integrator_summary(const nlohmann::json& meta) {
  if (!meta.is_object() || !meta.contains("cg_iterations_median")) return "";
  return "CG iterations per step median " + std::to_string(meta["cg_iterations_median"].get<int>()) + ", max " +
         std::to_string(meta["cg_iterations_max"].get<int>()) + "; largest final residual " +
         format_number(meta["cg_residual_max"].get<double>()) + "; " +
         std::to_string(meta["cg_unconverged_steps"].get<int64_t>()) + " steps stopped at cg_max_iterations";
}

std::string integrator_progress(const Backend& backend) {
  const IntegratorStats* s = backend.integrator_stats();
  if (!s || s->unconverged_steps == 0) return "";
  return "CG at its limit in " + std::to_string(s->unconverged_steps) + " of " + std::to_string(s->steps()) + " steps";
}

}  // namespace organsim
