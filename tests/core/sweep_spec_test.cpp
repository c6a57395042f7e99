// Sweep files: expansion into cases, stable names, each case's scenario, and
// every bad sweep file refused with a message naming the entry at fault.
#include "core/sweep/sweep_spec.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/sweep/case_names.h"
#include "core/sweep/field_path.h"
#include "core/util/error.h"

namespace organsim {
namespace sweep_spec_test {
namespace {

namespace fs = std::filesystem;

const std::string kBase = std::string(ORGANSIM_SOURCE_DIR) + "/scenarios/stress/gentle_push.json";

// Writes `body` (the sweep file without its "scenario" line) and loads it.
Sweep load(const std::string& test, const std::string& body, const std::string& scenario = kBase) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "sweep_spec" / test;
  fs::create_directories(dir);
  const fs::path file = dir / "sweep.json";
  std::ofstream(file) << "{\"scenario\": \"" << scenario << "\", " << body << "}";
  return load_sweep(file);
}

// The message of the error load() throws, with its kind checked.
std::string refusal(const std::string& test, const std::string& body, ErrorKind kind = ErrorKind::Scenario) {
  try {
    load(test, body);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), kind) << e.what();
    EXPECT_NE(std::string(e.what()).find("sweep.json"), std::string::npos) << "names the sweep file: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << body;
  return {};
}

nlohmann::json scenario_of(const SweepCase& c) { return nlohmann::json::parse(c.scenario_text); }

TEST(SweepSpec, GridIsTheCartesianProductLastFieldFastest) {
  const Sweep s = load("grid", R"("grid": {"material.young_modulus": [3000, 5000, 8000],
                                           "tool.keyframes[1].position[2]": [0.046, 0.044]})");
  ASSERT_EQ(s.cases.size(), 6u);
  const std::vector<std::string> names{"young_modulus=3000,position2=0.046", "young_modulus=3000,position2=0.044",
                                       "young_modulus=5000,position2=0.046", "young_modulus=5000,position2=0.044",
                                       "young_modulus=8000,position2=0.046", "young_modulus=8000,position2=0.044"};
  for (size_t i = 0; i < names.size(); ++i) EXPECT_EQ(s.cases[i].name, names[i]);
  // Each case's scenario has its values at their paths and nothing else changed.
  const nlohmann::json base = nlohmann::json::parse(std::ifstream(kBase));
  const nlohmann::json c3 = scenario_of(s.cases[3]);
  EXPECT_EQ(c3["material"]["young_modulus"], 5000);
  EXPECT_EQ(c3["tool"]["keyframes"][1]["position"][2], 0.044);
  EXPECT_EQ(c3["tool"]["keyframes"][0], base["tool"]["keyframes"][0]);
  EXPECT_EQ(c3["time"], base["time"]);
  // The mesh is absolute, so the scenario runs from the case's own folder.
  const fs::path mesh = c3["mesh"]["tet"].get<std::string>();
  EXPECT_TRUE(mesh.is_absolute()) << mesh;
  EXPECT_TRUE(fs::exists(mesh)) << mesh;
  EXPECT_NE(s.cases[3].scenario_hash, s.cases[2].scenario_hash);
  EXPECT_EQ(s.swept_paths, (std::vector<std::string>{"material.young_modulus", "tool.keyframes[1].position[2]"}));
}

TEST(SweepSpec, NamesComeFromValuesSoAddingAValueKeepsTheOthers) {
  const Sweep a = load("stable_a", R"("grid": {"material.young_modulus": [3000, 5000]})");
  const Sweep b = load("stable_b", R"("grid": {"material.young_modulus": [4000, 3000, 5000]})");
  EXPECT_EQ(a.cases[0].name, b.cases[1].name);
  EXPECT_EQ(a.cases[1].name, b.cases[2].name);
  EXPECT_EQ(a.cases[0].scenario_hash, b.cases[1].scenario_hash);  // same values, same scenario
  // Loading twice gives the same names and scenario text.
  const Sweep again = load("stable_a", R"("grid": {"material.young_modulus": [3000, 5000]})");
  EXPECT_EQ(again.cases[1].name, a.cases[1].name);
  EXPECT_EQ(again.cases[1].scenario_text, a.cases[1].scenario_text);
}

TEST(SweepSpec, LabelsGrowUntilTheyAreUnique) {
  EXPECT_EQ(field_labels({"tool.keyframes[0].t", "tool.keyframes[1].t", "time.dt"}),
            (std::vector<std::string>{"keyframes0.t", "keyframes1.t", "dt"}));
  EXPECT_EQ(field_labels({"a.x.k", "b.x.k"}), (std::vector<std::string>{"a.x.k", "b.x.k"}));
}

TEST(SweepSpec, ValueTextAndLongNames) {
  EXPECT_EQ(value_text(nlohmann::json(1e-05)), "1e-05");
  EXPECT_EQ(value_text(nlohmann::json("../meshes/patient 07.off")), "patient-07.off");
  EXPECT_EQ(value_text(nlohmann::json::parse("[0.03, 0, 0.05]")), "0.03-0-0.05");
  const std::string long_a = case_name({std::string(95, 'a'), "x=1", "y=2"});
  const std::string long_b = case_name({std::string(95, 'a'), "x=1", "y=3"});
  EXPECT_EQ(long_a.size(), kMaxCaseNameLength);
  EXPECT_NE(long_a, long_b);  // cut at the same place, told apart by the hash
  EXPECT_EQ(long_a, case_name({std::string(95, 'a'), "x=1", "y=2"}));
  EXPECT_EQ(case_name_problem(long_a), "");
}

TEST(SweepSpec, CasesTimesGridAndZipPairs) {
  const Sweep s = load("cases_zip", R"("cases": [{"name": "soft", "material.young_modulus": 3000},
                                                {"name": "stiff", "material.young_modulus": 8000}],
                                      "zip": {"material.density": [1000, 1100], "material.viscous_damping": [2, 3]},
                                      "set": {"time.duration": 0.01})");
  ASSERT_EQ(s.cases.size(), 4u);
  EXPECT_EQ(s.cases[0].name, "soft,density=1000,viscous_damping=2");
  EXPECT_EQ(s.cases[1].name, "soft,density=1100,viscous_damping=3");
  EXPECT_EQ(s.cases[3].name, "stiff,density=1100,viscous_damping=3");
  const nlohmann::json c = scenario_of(s.cases[3]);
  EXPECT_EQ(c["material"]["young_modulus"], 8000);
  EXPECT_EQ(c["material"]["density"], 1100);
  EXPECT_EQ(c["material"]["viscous_damping"], 3);
  EXPECT_EQ(c["time"]["duration"], 0.01);  // "set" reaches every case, not the names
}

TEST(SweepSpec, NullRemovesAFieldSoACaseCanSwitchTheMeshKind) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "sweep_spec" / "mesh_kind";
  fs::create_directories(dir);
  fs::copy_file(fs::path(ORGANSIM_SOURCE_DIR) / "examples/box.off", dir / "box.off",
                fs::copy_options::overwrite_existing);
  const Sweep s = load("mesh_kind", R"("cases": [{"name": "meshed", "mesh.tet": null, "mesh.surface": "box.off"}])");
  const nlohmann::json c = scenario_of(s.cases[0]);
  EXPECT_FALSE(c["mesh"].contains("tet"));
  EXPECT_EQ(fs::path(c["mesh"]["surface"].get<std::string>()), fs::absolute(dir / "box.off"));
}

TEST(SweepSpec, MeshFileInASweepIsRelativeToTheSweepFile) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "sweep_spec" / "mesh_relative";
  fs::create_directories(dir);
  fs::copy_file(fs::path(ORGANSIM_SOURCE_DIR) / "scenarios/stress/box.mesh", dir / "other.mesh",
                fs::copy_options::overwrite_existing);
  const Sweep s = load("mesh_relative", R"("cases": [{"name": "other", "mesh.tet": "other.mesh"}])");
  EXPECT_EQ(fs::path(scenario_of(s.cases[0])["mesh"]["tet"].get<std::string>()), fs::absolute(dir / "other.mesh"));
}

// Each bad sweep file is refused by load_sweep (before any run) with the
// entry at fault in the message.
TEST(SweepSpec, BadSweepFilesAreRefusedNamingTheEntry) {
  auto expect_in = [](const std::string& message, const std::string& part) {
    EXPECT_NE(message.find(part), std::string::npos) << "expected \"" << part << "\" in: " << message;
  };
  // An unknown field path: the scenario parser's own message, and the entry.
  std::string m = refusal("unknown_field", R"("grid": {"material.young_modulu": [1, 2]})");
  expect_in(m, "material.young_modulu: unknown field");
  expect_in(m, R"(set by grid["material.young_modulu"][0])");
  // A value of the wrong type, in the second entry only.
  m = refusal("wrong_type", R"("grid": {"material.young_modulus": [3000, "soft"]})");
  expect_in(m, "material.young_modulus: expected a number, got a string");
  expect_in(m, R"(grid["material.young_modulus"][1])");
  // Out of the parser's range.
  m = refusal("negative", R"("cases": [{"name": "a", "time.dt": -1}])");
  expect_in(m, "time.dt: expected a value > 0");
  expect_in(m, R"(cases[0]["time.dt"])");
  // Empty grid, empty list, nothing to sweep.
  expect_in(refusal("empty_grid", R"("grid": {})"), "grid: expected an object");
  expect_in(refusal("empty_list", R"("grid": {"time.dt": []})"), R"(grid["time.dt"]: expected a non-empty array)");
  expect_in(refusal("nothing", R"("set": {"time.dt": 0.0001})"), "nothing to sweep");
  // Duplicate case names, explicit or from equal values.
  expect_in(refusal("dup_names", R"("cases": [{"name": "a"}, {"name": "a", "time.dt": 0.0001}])"),
            "two cases are named \"a\" (cases[0]; and cases[1])");
  expect_in(refusal("dup_values", R"("grid": {"time.dt": [0.0001, 0.0001]})"), "two cases are named \"dt=0.0001\"");
  // Malformed path, index out of range, a key below a number.
  expect_in(refusal("bad_path", R"("grid": {"tool..radius": [1]})"),
            R"(grid["tool..radius"]: not a scenario field path)");
  m = refusal("index", R"("grid": {"tool.keyframes[5].t": [0.1]})");
  expect_in(m, R"(grid["tool.keyframes[5].t"])");
  expect_in(m, "index out of range (the base scenario's array has 2 elements)");
  expect_in(refusal("below_number", R"("grid": {"time.dt.x": [1]})"), "time.dt is a number in the base scenario");
  // zip lists of different lengths.
  expect_in(refusal("zip", R"("zip": {"time.dt": [0.0001, 0.0002], "material.density": [1000]})"),
            R"(zip["material.density"]: has 1 values, but zip["time.dt"] has 2)");
  // One field in two places.
  expect_in(refusal("twice", R"("set": {"time.dt": 0.0001}, "grid": {"time.dt": [0.0002]})"),
            R"(the field time.dt is also set by set["time.dt"])");
  // A missing mesh file is found now, not when the case runs.
  m = refusal("no_mesh", R"("cases": [{"name": "p07", "mesh.tet": "missing.mesh"}])");
  expect_in(m, "mesh: no such file");
  expect_in(m, "cases[0][\"mesh.tet\"]");
  // Unknown top-level field, bad case name.
  expect_in(refusal("top", R"("grid": {"time.dt": [0.0001]}, "gird": 1)"), "gird: unknown field");
  expect_in(refusal("name", R"("cases": [{"name": "../x"}])"), "cases[0].name: a case name must not start with '.'");
}

TEST(SweepSpec, BaseScenarioErrorsNameTheScenarioFile) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "sweep_spec" / "bad_base";
  fs::create_directories(dir);
  std::ofstream(dir / "base.json") << R"({"mesh": {"tet": "x.mesh"}, "materail": {}})";
  try {
    load("bad_base", R"("grid": {"time.dt": [0.0001]})", (dir / "base.json").string());
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("base.json: materail: unknown field"), std::string::npos) << e.what();
  }
}

TEST(FieldPath, SetsExistingAndNewFields) {
  nlohmann::json j = {{"a", {{"b", {1, 2, 3}}}}};
  set_field(j, "a.b[2]", 9);
  set_field(j, "a.c", "x");
  set_field(j, "d.e", true);
  EXPECT_EQ(j["a"]["b"][2], 9);
  EXPECT_EQ(j["a"]["c"], "x");
  EXPECT_EQ(j["d"]["e"], true);
  set_field(j, "a.c", nullptr);  // null removes
  EXPECT_FALSE(j["a"].contains("c"));
  EXPECT_THROW(set_field(j, "a.b[3]", 1), Error);
  EXPECT_THROW(set_field(j, "a.c[0]", 1), Error);
  EXPECT_THROW(parse_field_path("a[x]"), Error);
  EXPECT_THROW(parse_field_path("a.b."), Error);
  ASSERT_NE(find_field(j, "a.b[2]"), nullptr);
  EXPECT_EQ(*find_field(j, "a.b[2]"), 9);
  EXPECT_EQ(find_field(j, "a.z"), nullptr);
}

}  // namespace
}  // namespace sweep_spec_test
}  // namespace organsim
