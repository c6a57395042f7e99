#pragma once
// A sweep file: a base scenario and the values to vary, expanded into cases.
//   {"scenario": "gentle_push.json",              relative to the sweep file
//    "set":   {"time.duration": 0.05},            the same in every case (not in names)
//    "cases": [{"name": "soft", "material.young_modulus": 3000}, ...],   a list
//    "zip":   {"a.b": [1, 2], "c.d": [3, 4]},     paired lists: (1,3), (2,4)
//    "grid":  {"material.young_modulus": [3000, 5000], "time.dt": [1e-4, 2e-4]}}
// Any of cases, zip and grid; the cases are their cartesian product, cases
// outermost, grid fields in file order, the last varying fastest. Every
// case's scenario is built and parsed here, so a bad sweep file is refused
// before anything runs, naming the entry at fault. See docs/sweep.md.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace organsim {

// More cases than a sweep runs in practice: the file is refused instead of
// building (and parsing) every scenario.
inline constexpr size_t kMaxSweepCases = 100'000;

struct CaseOverride {
  std::string path;      // scenario field, e.g. "tool.keyframes[1].position[2]"
  nlohmann::json value;  // as written in the sweep file
  std::string origin;    // where in the sweep file, e.g. grid["material.young_modulus"][1]
};

struct SweepCase {
  std::string name;                     // stable: from the swept values (case_names.h)
  std::vector<CaseOverride> overrides;  // the swept values of this case
  std::string scenario_text;            // the case's scenario (JSON, file paths absolute)
  std::string scenario_hash;            // text_hash(scenario_text)
  bool writes_forces = true;            // the scenario asks for forces.json
};

struct Sweep {
  std::filesystem::path file;            // the sweep file as given
  std::filesystem::path scenario;        // the base scenario
  std::vector<CaseOverride> fixed;       // "set"
  std::vector<std::string> swept_paths;  // every swept field, in expansion order
  std::vector<SweepCase> cases;          // expansion order
};

// Reads, expands and validates. Throws Error(Input) for an unreadable file
// or invalid JSON, Error(Scenario) naming the sweep file and entry for
// anything else (unknown or malformed field path, a value the scenario
// parser refuses, an empty grid, lists of different lengths in zip,
// duplicate case names, a mesh file that does not exist).
Sweep load_sweep(const std::filesystem::path& file);

// As load_sweep, from the file's text (the fuzz harness enters here).
Sweep parse_sweep_text(const std::string& text, const std::filesystem::path& file);

// As load_sweep, from the parsed file (`file` names it in messages and
// locates relative paths).
Sweep parse_sweep(const nlohmann::ordered_json& j, const std::filesystem::path& file);

}  // namespace organsim
