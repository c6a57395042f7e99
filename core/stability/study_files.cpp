#include "core/stability/study_files.h"

#include <cmath>

#include "core/sim/step_plan.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "core/util/json_fields.h"

namespace organsim {
namespace {

using json = nlohmann::json;

constexpr const char* kPlanFormat = "organsim study plan 1";
constexpr const char* kReferenceFormat = "organsim study reference 1";
constexpr const char* kRunFormat = "organsim study run 1";

// JSON has no infinity or NaN (nlohmann would write null and lose which):
// those are written as strings, every finite number as its exact text.
json number(double v) {
  if (std::isfinite(v)) return v;
  return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
}

json points_json(const std::vector<Vec3>& points) {
  json a = json::array();
  for (const Vec3& p : points)
    for (int k = 0; k < 3; ++k) a.push_back(number(p[k]));
  return a;
}

// A configuration's or outcome's integrator: absent (files written before
// the integrator was an axis) means "verlet".
std::string integrator_of(const JsonFields& r, const json& j, const std::string& where) {
  if (!j.is_object() || !j.contains("integrator")) return "verlet";
  const std::string name = r.text(j, "integrator", where);
  for (Integrator i : {Integrator::Verlet, Integrator::ImplicitEuler, Integrator::ImplicitDamping})
    if (name == integrator_name(i)) return name;
  throw r.error(where + ".integrator", "\"verlet\", \"implicit_euler\" or \"implicit_damping\"");
}

}  // namespace

json plan_json(const StudyPlan& plan) {
  json configurations = json::array();
  for (const StudyConfiguration& c : plan.configurations)
    configurations.push_back(
        {{"integrator", c.integrator}, {"backend", c.backend}, {"precision", c.precision}, {"substeps", c.substeps}});
  return {{"format", kPlanFormat}, {"request", plan.request}, {"head", plan.head}, {"configurations", configurations}};
}

StudyPlan parse_study_plan(const json& j, const std::string& source) {
  const JsonFields r(source);
  r.format(j, kPlanFormat);
  StudyPlan plan;
  plan.request = r.field(j, "request", "file");
  if (!plan.request.is_object()) throw r.error("request", "an object");
  plan.head = r.field(j, "head", "file");
  plan.dt_crit = r.number(r.field(plan.head, "stability", "head"), "dt_crit", "head.stability");
  if (!(plan.dt_crit > 0)) throw r.error("head.stability.dt_crit", "a positive step in s");
  // What a shard compares with its own model.
  const json& model = r.field(plan.head, "model", "head");
  r.whole(model, "points", "head.model", 1, int64_t(1) << 40);
  r.whole(model, "tets", "head.model", 0, int64_t(1) << 40);
  // What the table's summary line reads.
  const json& reference = r.field(plan.head, "reference", "head");
  r.number(reference, "dt_half", "head.reference");
  r.number(reference, "halving_position_change_max", "head.reference");
  r.flag(reference, "converged", "head.reference");
  if (plan.head.contains("runs")) throw r.error("head.runs", "none (the runs are in study_runs/)");
  const json& configurations = r.array(j, "configurations", "file");
  for (size_t i = 0; i < configurations.size(); ++i) {
    const std::string where = "configurations[" + std::to_string(i) + "]";
    const json& c = configurations[i];
    plan.configurations.push_back({r.text(c, "backend", where), r.text(c, "precision", where),
                                   static_cast<int32_t>(r.whole(c, "substeps", where, 1, 1 << 30)),
                                   integrator_of(r, c, where)});
  }
  return plan;
}

json trajectory_json(const Trajectory& t) {
  json positions = json::array();
  for (const auto& sample : t.positions) positions.push_back(points_json(sample));
  return {{"format", kReferenceFormat}, {"latency_ticks", t.latency_ticks}, {"ticks", t.ticks},
          {"positions", positions}, {"force", points_json(t.force)}};
}

Trajectory parse_trajectory(const json& j, const std::string& source) {
  const JsonFields r(source);
  r.format(j, kReferenceFormat);
  Trajectory t;
  t.latency_ticks = static_cast<int32_t>(r.whole(j, "latency_ticks", "file", 0, 1 << 20));
  const json& ticks = r.array(j, "ticks", "file");
  for (size_t i = 0; i < ticks.size(); ++i) {
    const int64_t tick = ticks[i].is_number_integer() ? ticks[i].get<int64_t>() : -1;
    // Increasing: compare_trajectories walks both lists in step.
    if (tick < 0 || (i > 0 && tick <= t.ticks.back()))
      throw r.error("ticks[" + std::to_string(i) + "]", "a tick index above the one before");
    t.ticks.push_back(tick);
  }
  const json& positions = r.array(j, "positions", "file");
  if (positions.size() != t.ticks.size()) throw r.error("positions", "one sample per tick (" + std::to_string(t.ticks.size()) + ")");
  for (size_t i = 0; i < positions.size(); ++i) {
    t.positions.push_back(r.points(positions[i], "positions[" + std::to_string(i) + "]"));
    if (t.positions.back().size() != t.positions.front().size())
      throw r.error("positions[" + std::to_string(i) + "]", "as many points as positions[0]");
  }
  t.force = r.points(r.field(j, "force", "file"), "force");
  return t;
}

json outcome_record_json(const StudyOutcome& o) {
  return {{"format", kRunFormat},
          {"integrator", o.integrator},
          {"backend", o.backend},
          {"precision", o.precision},
          {"substeps", o.substeps},
          {"device", o.device},
          {"dt", number(o.dt)},
          {"ran", o.ran},
          {"stable", o.stable},
          {"reason", o.reason},
          {"simulated", number(o.simulated)},
          {"wall", number(o.wall)},
          {"steps_per_second", number(o.steps_per_second)},
          {"errors",
           {{"position_max", number(o.errors.position_max)},
            {"position_rms", number(o.errors.position_rms)},
            {"force_rms", number(o.errors.force_rms)},
            {"samples", o.errors.samples},
            {"ticks", o.errors.ticks}}}};
}

StudyOutcome parse_outcome_record(const json& j, const std::string& source) {
  const JsonFields r(source);
  r.format(j, kRunFormat);
  StudyOutcome o;
  o.integrator = integrator_of(r, j, "file");
  o.backend = r.text(j, "backend", "file");
  o.precision = r.text(j, "precision", "file");
  o.substeps = static_cast<int32_t>(r.whole(j, "substeps", "file", 1, 1 << 30));
  o.device = r.text(j, "device", "file");
  o.dt = r.number(j, "dt", "file");
  o.ran = r.flag(j, "ran", "file");
  o.stable = r.flag(j, "stable", "file");
  o.reason = r.text(j, "reason", "file");
  o.simulated = r.number(j, "simulated", "file");
  o.wall = r.number(j, "wall", "file");
  o.steps_per_second = r.number(j, "steps_per_second", "file");
  const json& e = r.field(j, "errors", "file");
  o.errors.position_max = r.number(e, "position_max", "errors");
  o.errors.position_rms = r.number(e, "position_rms", "errors");
  o.errors.force_rms = r.number(e, "force_rms", "errors");
  o.errors.samples = r.whole(e, "samples", "errors", 0, int64_t(1) << 40);
  o.errors.ticks = r.whole(e, "ticks", "errors", 0, int64_t(1) << 40);
  return o;
}

json parse_study_json(const std::string& text, const std::string& source) { return JsonFields(source).parse(text); }

json read_study_file(const std::string& path) { return parse_study_json(read_text_file(path), path); }

}  // namespace organsim
