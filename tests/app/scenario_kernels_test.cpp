// Which CPU kernel every shipped scenario runs on, as a user sees it: the
// `backend:` line of `organsim run --plan` (at the start) and the run's own
// device lines (`run:` at the start, `device: ... (at the end)` when it
// changed), before and after the scenario's topology events (cut, tear,
// sutures). The CPU backend has one kernel and refuses a plan it cannot run
// (simd_kernel_unsupported), so every shipped scenario must run on it from
// start to end: a change of kernel must be a decision written in
// kExpectedKernels, not an accident.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace scenario_kernels_test {
namespace {

namespace fs = std::filesystem;

// Every scenario in scenarios/ (not stress/ or sweeps/), the kernel it runs
// on before its topology events and after them (the same for a scenario
// without events), whatever the CPU: the simd kernel (on the CPU's best
// target, which the device line names beside it) runs every plan
// (simd_kernel_unsupported in core/sim/cpu_kernel_simd.cpp), sutures and the
// shear element included.
struct ScenarioKernel {
  const char* scenario;
  const char* before;  // --plan and the run's `run:` line
  const char* after;   // the kernel at the end of the run, after every event
};
constexpr ScenarioKernel kExpectedKernels[] = {
    {"default", "simd", "simd"},
    {"liver_push", "simd", "simd"},
    {"liver_probe", "simd", "simd"},
    {"liver_grasp", "simd", "simd"},
    {"liver_pull", "simd", "simd"},
    {"liver7750_push", "simd", "simd"},
    {"liver7750_realtime", "simd", "simd"},
    {"liver_cut", "simd", "simd"},
    {"liver_suture", "simd", "simd"},
    {"bar_tear", "simd", "simd"},
    {"palpation", "simd", "simd"},
};

// "simd" from "..., simd (avx2) kernel)" or "..., simd (sse4) kernel (at
// the end)": the first word after the last ", " before " kernel" on `line` (the
// kernel, not its target); "" when the line names no kernel.
std::string kernel_on(const std::string& line) {
  const size_t at = line.rfind(" kernel");
  if (at == std::string::npos) return "";
  const size_t comma = line.rfind(", ", at);
  const size_t from = comma == std::string::npos ? 0 : comma + 2;
  const std::string name = line.substr(from, at - from);
  return name.substr(0, name.find(' '));
}

// The first line of `text` that starts with `prefix` and names a kernel.
std::string line_naming_kernel(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0 && !kernel_on(line).empty()) return line;
  }
  return "";
}

const fs::path kScenarios = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios";
const fs::path kDir = fs::path(ORGANSIM_TEST_TMP) / "scenario_kernels";

// A scenario's surface meshed once per distinct mesh definition (the 2500-point
// liver is shared by five scenarios): `organsim mesh` with the scenario's
// options writes the tet mesh the scenario itself would make.
fs::path tet_mesh_for(const nlohmann::json& mesh) {
  static std::map<std::string, fs::path> meshed;
  const std::string key = mesh.dump();
  if (auto it = meshed.find(key); it != meshed.end()) return it->second;
  const fs::path out = kDir / ("mesh" + std::to_string(meshed.size()) + ".mesh");
  const auto r = test::run_organsim("mesh '" + (kScenarios / mesh["surface"].get<std::string>()).string() +
                                        "' --target-points " + std::to_string(mesh["options"]["target_points"].get<int>()) +
                                        " -o '" + out.string() + "'",
                                    kDir / "meshing");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  meshed[key] = out;
  return out;
}

// The scenario as shipped, except: a surface becomes its tet mesh (above), a
// path is made absolute, no settling, forces only (no frames), `auto` is the
// CPU backend (below), and it stops a
// few ticks after its last timed event (cut keyframes, sutures); a tear has
// no time, so a scenario with one runs to its end.
nlohmann::json test_copy(const nlohmann::json& shipped) {
  nlohmann::json s = shipped;
  if (s["mesh"].contains("surface")) {
    EXPECT_EQ(s["mesh"]["options"].size(), 1u) << "only target_points is passed on to organsim mesh";
    s["mesh"] = {{"tet", tet_mesh_for(s["mesh"]).string()}};
  } else if (s["mesh"].contains("tet")) {
    s["mesh"]["tet"] = (kScenarios / s["mesh"]["tet"].get<std::string>()).string();
  } else {
    s["mesh"]["image"] = (kScenarios / s["mesh"]["image"].get<std::string>()).string();
  }
  const double tick = s["time"]["dt"].get<double>() * s["time"]["substeps"].get<int>();
  double last = 0;
  bool tear = false;
  for (const auto& e : s.value("events", nlohmann::json::array())) {
    if (e.contains("cut")) last = std::max(last, e["cut"]["keyframes"].back()["t"].get<double>());
    if (e.contains("suture")) last = std::max(last, e["suture"]["t"].get<double>());
    if (e.contains("tear")) tear = true;
  }
  if (!tear) s["time"]["duration"] = std::min(s["time"]["duration"].get<double>(), last + 5 * tick);
  s["time"].erase("settle");
  // `auto` (no backend given) is the CPU backend in float wherever there is no
  // hardware GPU; a GPU would take it to GL, which has no CPU kernel.
  if (!s.contains("backend")) s["backend"] = {{"name", "cpu"}, {"precision", "float"}};
  s["outputs"] = {{"forces", true}};
  return s;
}

class ScenarioKernels : public ::testing::TestWithParam<ScenarioKernel> {};

TEST_P(ScenarioKernels, PlanAndRunNameTheExpectedKernelBeforeAndAfterTheEvents) {
  const ScenarioKernel& expected = GetParam();
  const std::string before = expected.before, after = expected.after;
  const std::string name = expected.scenario;
  const fs::path dir = kDir / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  const nlohmann::json shipped = nlohmann::json::parse(test::slurp(kScenarios / (name + ".json")));
  const nlohmann::json copy = test_copy(shipped);
  const fs::path scene = dir / (name + ".json");
  std::ofstream(scene) << copy.dump(2);

  const auto plan = test::run_organsim("run '" + scene.string() + "' --plan", dir / "plan");
  ASSERT_EQ(plan.exit_code, 0) << plan.err;
  const std::string plan_line = line_naming_kernel(plan.out, "backend:  cpu (");
  EXPECT_EQ(kernel_on(plan_line), before) << plan.out;

  const auto run = test::run_organsim("run '" + scene.string() + "' -o '" + (dir / "out").string() + "'", dir / "run");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string start_line = line_naming_kernel(run.out, "run:      ");
  EXPECT_EQ(kernel_on(start_line), before) << run.out;
  // `device: ... (at the end)` is printed only when the device changed.
  const std::string end_line = line_naming_kernel(run.out, "device:   ");
  EXPECT_EQ(kernel_on(end_line.empty() ? start_line : end_line), after) << run.out;

  // The events did happen in the shortened run: "after" is after them.
  const auto log = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  ASSERT_EQ(log["meta"]["completed"], true);
  std::set<std::string> kinds_asked, kinds_done;
  for (const auto& e : shipped.value("events", nlohmann::json::array())) kinds_asked.insert(e.begin().key());
  for (const auto& e : log["meta"].value("events", nlohmann::json::array())) {
    std::istringstream kinds(e["kind"].get<std::string>());  // "cut", or several joined by "+"
    for (std::string k; std::getline(kinds, k, '+');) kinds_done.insert(k);
  }
  EXPECT_EQ(kinds_done, kinds_asked);
}

std::string scenario_name(const ::testing::TestParamInfo<ScenarioKernel>& info) { return info.param.scenario; }

INSTANTIATE_TEST_SUITE_P(Shipped, ScenarioKernels, ::testing::ValuesIn(kExpectedKernels), scenario_name);

// The table holds every shipped scenario, so a new one gets an expectation.
TEST(ScenarioKernelsTable, ListsEveryShippedScenario) {
  std::set<std::string> shipped, listed;
  for (const auto& e : fs::directory_iterator(kScenarios)) {
    if (e.path().extension() == ".json") shipped.insert(e.path().stem().string());
  }
  for (const ScenarioKernel& k : kExpectedKernels) listed.insert(k.scenario);
  EXPECT_EQ(listed, shipped);
}

}  // namespace
}  // namespace scenario_kernels_test
}  // namespace organsim
