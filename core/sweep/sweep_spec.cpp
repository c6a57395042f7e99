#include "core/sweep/sweep_spec.h"

#include <algorithm>
#include <map>

#include "core/scenario/json_reader.h"
#include "core/scenario/scenario.h"
#include "core/sweep/case_names.h"
#include "core/sweep/field_path.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

namespace fs = std::filesystem;

namespace {

// One value of an axis: the overrides it sets, and a name when the sweep
// file gives one ("cases" entries only).
struct AxisEntry {
  std::vector<CaseOverride> overrides;
  std::string name;
  std::string origin;  // e.g. cases[2] or grid["time.dt"][1]
};
using Axis = std::vector<AxisEntry>;

class SweepReader {
 public:
  explicit SweepReader(const fs::path& file) : file_(file.string()) {}

  Error error(const std::string& where, const std::string& message) const {
    std::string text = file_ + ": ";
    if (!where.empty()) text.append(where).append(": ");
    return Error(ErrorKind::Scenario, text + message);
  }

  static nlohmann::json plain(const nlohmann::ordered_json& j) { return nlohmann::json::parse(j.dump()); }

  static std::string quoted(const std::string& key) { return std::string("[\"").append(key).append("\"]"); }

  // A field path used as a key: well formed, or an error naming the entry.
  void check_path(const std::string& path, const std::string& where) const {
    try {
      parse_field_path(path);
    } catch (const Error& e) {
      throw error(where, std::string("not a scenario field path: ") + e.what());
    }
  }

 private:
  std::string file_;
};

Axis read_cases(const nlohmann::ordered_json& j, const SweepReader& r) {
  if (!j.is_array() || j.empty())
    throw r.error("cases", "expected a non-empty array of cases ({\"name\": ..., \"field.path\": value, ...})");
  Axis axis;
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string at = "cases[" + std::to_string(i) + "]";
    if (!j[i].is_object()) throw r.error(at, "expected an object {\"name\": ..., \"field.path\": value, ...}");
    AxisEntry entry;
    entry.origin = at;
    for (const auto& item : j[i].items()) {
      if (item.key() == "name") {
        if (!item.value().is_string()) throw r.error(at + ".name", "expected a string");
        entry.name = item.value().get<std::string>();
        if (const std::string why = case_name_problem(entry.name); !why.empty())
          throw r.error(at + ".name", why + " (got \"" + entry.name + "\")");
        continue;
      }
      r.check_path(item.key(), at + SweepReader::quoted(item.key()));
      entry.overrides.push_back({item.key(), SweepReader::plain(item.value()), at + SweepReader::quoted(item.key())});
    }
    axis.push_back(std::move(entry));
  }
  return axis;
}

// Checks a {"field.path": [values...]} section and returns its lists.
std::vector<std::pair<std::string, nlohmann::json>> read_lists(const nlohmann::ordered_json& j,
                                                               const std::string& section, const SweepReader& r) {
  if (!j.is_object() || j.empty())
    throw r.error(section, "expected an object {\"field.path\": [values, ...], ...} with at least one field");
  std::vector<std::pair<std::string, nlohmann::json>> lists;
  for (const auto& item : j.items()) {
    const std::string at = section + SweepReader::quoted(item.key());
    r.check_path(item.key(), at);
    if (!item.value().is_array() || item.value().empty()) throw r.error(at, "expected a non-empty array of values");
    lists.emplace_back(item.key(), SweepReader::plain(item.value()));
  }
  return lists;
}

std::vector<Axis> read_grid(const nlohmann::ordered_json& j, const SweepReader& r) {
  std::vector<Axis> axes;
  for (const auto& [path, values] : read_lists(j, "grid", r)) {
    Axis axis;
    for (size_t k = 0; k < values.size(); ++k) {
      const std::string at =
          std::string("grid").append(SweepReader::quoted(path)).append("[").append(std::to_string(k)).append("]");
      axis.push_back({{{path, values[k], at}}, "", at});
    }
    axes.push_back(std::move(axis));
  }
  return axes;
}

Axis read_zip(const nlohmann::ordered_json& j, const SweepReader& r) {
  const auto lists = read_lists(j, "zip", r);
  const size_t n = lists.front().second.size();
  for (const auto& [path, values] : lists) {
    if (values.size() != n)
      throw r.error("zip" + SweepReader::quoted(path), "has " + std::to_string(values.size()) + " values, but zip" +
                                                           SweepReader::quoted(lists.front().first) + " has " +
                                                           std::to_string(n) +
                                                           " (zip pairs the k-th values of every list)");
  }
  Axis axis(n);
  for (size_t k = 0; k < n; ++k) {
    axis[k].origin = "zip[" + std::to_string(k) + "]";
    for (const auto& [path, values] : lists)
      axis[k].overrides.push_back(
          {path, values[k],
           std::string("zip").append(SweepReader::quoted(path)).append("[").append(std::to_string(k)).append("]")});
  }
  return axis;
}

// A file name given in the sweep file is relative to the sweep file.
void resolve_file_fields(nlohmann::json& scenario, const std::vector<CaseOverride>& overrides, const fs::path& dir) {
  for (const CaseOverride& o : overrides) {
    const auto& fields = scenario_file_fields();
    if (std::find(fields.begin(), fields.end(), o.path) == fields.end() || !o.value.is_string()) continue;
    fs::path p(o.value.get<std::string>());
    if (p.is_relative()) p = dir / p;
    set_field(scenario, o.path, fs::absolute(p).lexically_normal().string());
  }
}

std::string describe_origins(const std::vector<CaseOverride>& overrides) {
  std::string s;
  for (const CaseOverride& o : overrides) {
    if (!s.empty()) s += ", ";
    s += o.origin;
  }
  return s.empty() ? "no swept values" : s;
}

// Builds the case's scenario and parses it with the scenario parser; an
// error names the case and the sweep entry that set the field at fault.
void build_case_scenario(SweepCase& c, const nlohmann::json& base, const std::vector<CaseOverride>& fixed,
                         const fs::path& sweep_dir, const SweepReader& r, const fs::path& sweep_file) {
  nlohmann::json j = base;
  std::vector<CaseOverride> all = fixed;
  all.insert(all.end(), c.overrides.begin(), c.overrides.end());
  for (const CaseOverride& o : all) {
    try {
      set_field(j, o.path, o.value);
    } catch (const Error& e) {
      throw r.error(o.origin, e.what());
    }
  }
  resolve_file_fields(j, all, sweep_dir);
  const std::string source = sweep_file.string() + ": case \"" + c.name + "\"";
  Scenario s;
  try {
    s = parse_scenario(j, sweep_dir, source);
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const CaseOverride& o : all) {
      const std::string prefix = source + ": " + o.path;
      if (what.rfind(prefix, 0) == 0 &&
          (what.size() == prefix.size() || std::string(":.[").find(what[prefix.size()]) != std::string::npos))
        throw Error(e.kind(), what + " (set by " + o.origin + ")");
    }
    throw Error(e.kind(), what + " (the case sets " + describe_origins(c.overrides) + ")");
  }
  if (!fs::exists(s.mesh.path))
    throw Error(ErrorKind::Scenario, source + ": mesh: no such file " + s.mesh.path.string() + " (the case sets " +
                                         describe_origins(c.overrides) + ")");
  c.writes_forces = s.outputs.forces;
  c.scenario_text = j.dump(2) + "\n";
  c.scenario_hash = text_hash(c.scenario_text);
}

}  // namespace

Sweep parse_sweep(const nlohmann::ordered_json& j, const fs::path& file) {
  const SweepReader r(file);
  if (!j.is_object()) throw r.error("", "expected an object {\"scenario\": ..., \"grid\" | \"zip\" | \"cases\": ...}");
  for (const auto& item : j.items()) {
    static const std::vector<std::string> known{"description", "scenario", "set", "cases", "zip", "grid"};
    if (std::find(known.begin(), known.end(), item.key()) == known.end())
      throw r.error(item.key(), "unknown field (expected " + one_of(known) + ")");
  }
  Sweep sweep;
  sweep.file = file;
  const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
  if (!j.contains("scenario") || !j["scenario"].is_string() || j["scenario"].get<std::string>().empty())
    throw r.error("scenario", "expected the base scenario's file name (relative to the sweep file)");
  sweep.scenario = (dir / j["scenario"].get<std::string>()).lexically_normal();
  if (fs::path(j["scenario"].get<std::string>()).is_absolute()) sweep.scenario = j["scenario"].get<std::string>();

  if (j.contains("set")) {
    if (!j["set"].is_object()) throw r.error("set", "expected an object {\"field.path\": value, ...}");
    for (const auto& item : j["set"].items()) {
      const std::string at = "set" + SweepReader::quoted(item.key());
      r.check_path(item.key(), at);
      sweep.fixed.push_back({item.key(), SweepReader::plain(item.value()), at});
    }
  }
  std::vector<Axis> axes;
  if (j.contains("cases")) axes.push_back(read_cases(j["cases"], r));
  if (j.contains("zip")) axes.push_back(read_zip(j["zip"], r));
  if (j.contains("grid")) {
    for (Axis& a : read_grid(j["grid"], r)) axes.push_back(std::move(a));
  }
  if (axes.empty()) throw r.error("", "nothing to sweep: give \"grid\", \"zip\" or \"cases\"");

  // Every swept field once, and never also in "set" or in two sections.
  std::map<std::string, std::string> first_origin;
  for (const CaseOverride& o : sweep.fixed) first_origin[o.path] = o.origin;
  for (const Axis& axis : axes) {
    std::map<std::string, std::string> in_this_axis;
    for (const AxisEntry& e : axis) {
      for (const CaseOverride& o : e.overrides) {
        if (in_this_axis.count(o.path)) continue;
        in_this_axis[o.path] = o.origin;
        if (first_origin.count(o.path))
          throw r.error(o.origin, "the field " + o.path + " is also set by " + first_origin[o.path] +
                                      "; give each field in one place");
        sweep.swept_paths.push_back(o.path);
      }
    }
    for (const auto& [path, origin] : in_this_axis) first_origin[path] = origin;
  }
  const std::vector<std::string> labels = field_labels(sweep.swept_paths);
  std::map<std::string, std::string> label_of;
  for (size_t i = 0; i < labels.size(); ++i) label_of[sweep.swept_paths[i]] = labels[i];

  // The cartesian product, last axis fastest.
  size_t total = 1;
  for (const Axis& a : axes) {
    // Checked before multiplying: many small axes must not wrap around.
    if (a.size() > kMaxSweepCases / total)
      throw r.error("", "expands to more than " + std::to_string(kMaxSweepCases) + " cases");
    total *= a.size();
  }
  std::vector<size_t> at(axes.size(), 0);
  std::map<std::string, size_t> case_of_name;
  std::vector<std::string> case_origins;  // the entries each case combines, for messages
  for (size_t n = 0; n < total; ++n) {
    SweepCase c;
    std::vector<std::string> parts;
    std::string origins;
    for (size_t a = 0; a < axes.size(); ++a) {
      const AxisEntry& e = axes[a][at[a]];
      if (!origins.empty()) origins += " x ";
      origins += e.origin;
      if (!e.name.empty()) parts.push_back(e.name);
      for (const CaseOverride& o : e.overrides) {
        c.overrides.push_back(o);
        if (e.name.empty()) parts.push_back(label_of[o.path] + "=" + value_text(o.value));
      }
    }
    c.name = parts.empty() ? "base" : case_name(parts);
    if (const auto it = case_of_name.find(c.name); it != case_of_name.end())
      throw r.error("", "two cases are named \"" + c.name + "\" (" + case_origins[it->second] + "; and " + origins +
                            "); give distinct \"name\"s in \"cases\" or distinct values");
    case_of_name[c.name] = sweep.cases.size();
    case_origins.push_back(origins);
    sweep.cases.push_back(std::move(c));
    for (size_t a = axes.size(); a-- > 0;) {
      if (++at[a] < axes[a].size()) break;
      at[a] = 0;
    }
  }

  // The base must parse alone (its own errors name its file), then each case.
  load_scenario(sweep.scenario);
  const nlohmann::json base = scenario_json_with_absolute_paths(sweep.scenario);
  for (SweepCase& c : sweep.cases) build_case_scenario(c, base, sweep.fixed, dir, r, file);
  return sweep;
}

Sweep load_sweep(const fs::path& file) { return parse_sweep_text(read_text_file(file), file); }

Sweep parse_sweep_text(const std::string& text, const fs::path& file) {
  nlohmann::ordered_json j;
  try {
    j = nlohmann::ordered_json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw input_error(file.string(), std::string("invalid JSON: ") + e.what());
  }
  return parse_sweep(j, file);
}

}  // namespace organsim
