#include "core/sweep/sweep_plan.h"

#include <set>

#include "core/sweep/case_names.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "core/util/json_fields.h"

namespace organsim {

namespace fs = std::filesystem;

fs::path case_dir(const fs::path& outdir, const SweepCase& c) { return outdir / "cases" / c.name; }

nlohmann::json overrides_json(const SweepCase& c) {
  nlohmann::json o = nlohmann::json::object();
  for (const CaseOverride& v : c.overrides) o[v.path] = v.value;
  return o;
}

nlohmann::json plan_json(const Sweep& sweep) {
  nlohmann::json fixed = nlohmann::json::object();
  for (const CaseOverride& v : sweep.fixed) fixed[v.path] = v.value;
  nlohmann::json cases = nlohmann::json::array();
  for (const SweepCase& c : sweep.cases) {
    cases.push_back({{"name", c.name},
                     {"overrides", overrides_json(c)},
                     {"scenario_hash", c.scenario_hash},
                     {"writes_forces", c.writes_forces}});
  }
  return {{"sweep", fs::absolute(sweep.file).lexically_normal().string()},
          {"scenario", fs::absolute(sweep.scenario).lexically_normal().string()},
          {"set", fixed},
          {"swept", sweep.swept_paths},
          {"cases", cases}};
}

Sweep parse_plan(const std::string& text, const std::string& source) {
  const JsonFields r(source);
  const nlohmann::json j = r.parse(text);
  Sweep sweep;
  sweep.file = r.text(j, "sweep", "file");
  sweep.scenario = r.text(j, "scenario", "file");
  if (sweep.file.empty()) throw r.error("sweep", "the sweep file's path");
  if (sweep.scenario.empty()) throw r.error("scenario", "the base scenario's path");
  const nlohmann::json& swept = r.array(j, "swept", "file");
  for (size_t i = 0; i < swept.size(); ++i) {
    if (!swept[i].is_string()) throw r.error("swept[" + std::to_string(i) + "]", "a field path");
    sweep.swept_paths.push_back(swept[i].get<std::string>());
  }
  for (const auto& item : r.object(j, "set", "file").items()) sweep.fixed.push_back({item.key(), item.value(), "set"});
  const nlohmann::json& cases = r.array(j, "cases", "file");
  std::set<std::string> names;
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string where = "cases[" + std::to_string(i) + "]";
    const nlohmann::json& jc = cases[i];
    SweepCase c;
    c.name = r.text(jc, "name", where);
    // The name is a folder under OUTDIR/cases/: one safe path component.
    const std::string problem = case_name_problem(c.name);
    if (!problem.empty()) throw input_error(source, where + ".name: " + problem);
    if (!names.insert(c.name).second) throw r.error(where + ".name", "a name no other case has");
    const nlohmann::json& overrides = r.object(jc, "overrides", where);
    for (const std::string& p : sweep.swept_paths) {
      if (overrides.contains(p)) c.overrides.push_back({p, overrides.at(p), ""});
    }
    c.scenario_hash = r.text(jc, "scenario_hash", where);
    c.writes_forces = r.flag(jc, "writes_forces", where);
    sweep.cases.push_back(std::move(c));
  }
  return sweep;
}

Sweep read_plan(const fs::path& outdir) {
  const fs::path path = outdir / "cases.json";
  return parse_plan(read_text_file(path), path.string());
}

void write_plan(const fs::path& outdir, const Sweep& sweep, bool must_match) {
  const fs::path path = outdir / "cases.json";
  const std::string text = plan_json(sweep).dump(2) + "\n";
  if (fs::exists(path)) {
    const std::string old = read_text_file(path);
    if (old == text) return;
    if (must_match)
      throw Error(ErrorKind::Usage, path.string() +
                                        ": this folder holds another sweep's plan (its cases or values differ); "
                                        "run the whole sweep once without --shard to replace it, or use another -o");
  }
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

std::vector<CaseRecord> read_case_records(const Sweep& plan, const fs::path& outdir) {
  std::vector<CaseRecord> records;
  for (const SweepCase& c : plan.cases) {
    const fs::path dir = case_dir(outdir, c);
    CaseRecord r;
    r.state = current_state(c, dir);
    if (r.state != CaseState::Pending) r.status = read_case_status(dir);
    records.push_back(std::move(r));
  }
  return records;
}

nlohmann::json manifest_json(const Sweep& plan, const std::vector<CaseRecord>& records, ManifestCounts* counts) {
  ManifestCounts n;
  nlohmann::json cases = nlohmann::json::array();
  for (size_t i = 0; i < plan.cases.size(); ++i) {
    const SweepCase& c = plan.cases[i];
    const CaseRecord& record = records.at(i);
    nlohmann::json jc = {{"name", c.name}, {"overrides", overrides_json(c)}, {"status", to_string(record.state)}};
    if (record.state != CaseState::Pending && record.status) {
      const nlohmann::json r = to_json(*record.status);
      for (const char* key : {"exit_code", "signal", "error", "wall_seconds", "meta"}) jc[key] = r[key];
    }
    (record.state == CaseState::Done ? n.done : record.state == CaseState::Failed ? n.failed : n.pending) += 1;
    cases.push_back(std::move(jc));
  }
  if (counts) *counts = n;
  return {{"sweep", fs::absolute(plan.file).lexically_normal().string()},
          {"scenario", fs::absolute(plan.scenario).lexically_normal().string()},
          {"counts", {{"done", n.done}, {"failed", n.failed}, {"pending", n.pending}}},
          {"cases", cases}};
}

void write_manifest(const Sweep& plan, const std::vector<CaseRecord>& records, const fs::path& outdir,
                    ManifestCounts* counts) {
  const std::string text = manifest_json(plan, records, counts).dump(2) + "\n";
  write_file_atomically(outdir / "manifest.json", [&](std::ostream& out) { out << text; });
}

}  // namespace organsim
