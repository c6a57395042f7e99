// `organsim run` end to end on a small tet mesh: the force log, errors that
// name the JSON path, and --plan's list of passes.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "core/mesh/mesh_io.h"
#include "core/mesh/tet_mesh.h"
#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace run_cli_test {
namespace {

namespace fs = std::filesystem;
using test::run_organsim;

fs::path test_dir(const std::string& name) {
  const fs::path d = fs::path(ORGANSIM_TEST_TMP) / "run_cli" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A 4 cm cube of 4 x 4 x 4 cells (125 points, one at the top face's centre) next to the scenario, as medit.
void write_cube_mesh(const fs::path& dir) {
  write_tet_mesh(dir / "cube.mesh", make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.04, 0.04, 0.04), 4, 4, 4));
}

// 50 ms at 1 ms ticks; `extra` is merged over the base scenario.
fs::path write_scenario(const fs::path& dir, const nlohmann::json& extra) {
  nlohmann::json j = nlohmann::json::parse(R"({
    "mesh": {"tet": "cube.mesh"},
    "material": {"young_modulus": 5000},
    "fixed": [{"plane": {"point": [0, 0, 0.001], "normal": [0, 0, -1]}}],
    "time": {"duration": 0.05, "dt": 0.0001, "substeps": 10},
    "backend": {"threads": 1}
  })");
  j.merge_patch(extra);
  const fs::path file = dir / "scene.json";
  std::ofstream(file) << j.dump(2);
  return file;
}

const nlohmann::json kPushTool = nlohmann::json::parse(R"({"tool": {
  "radius": 0.01, "contact_stiffness": 200,
  "keyframes": [{"t": 0, "position": [0.02, 0.02, 0.055]}, {"t": 0.05, "position": [0.02, 0.02, 0.045]}]}})");

TEST(RunCli, WritesForcesJsonWithOneSamplePerTickAndExitsZero) {
  const fs::path dir = test_dir("ok");
  write_cube_mesh(dir);
  const fs::path scene = write_scenario(dir, kPushTool);
  const auto r = run_organsim("run '" + scene.string() + "' -o '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The command says where its outputs are.
  EXPECT_NE(r.out.find((dir / "out" / "forces.json").string()), std::string::npos) << r.out;
  // ...and lists what it wrote there (forces.png comes with the force log).
  EXPECT_NE(r.out.find("\n          forces.png\n"), std::string::npos) << r.out;

  const auto j = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  EXPECT_EQ(j["samples"]["t"].size(), 50u);  // 0.05 s / 1 ms
  EXPECT_EQ(j["samples"]["force"].size(), 50u);
  EXPECT_EQ(j["meta"]["points"], 125);
  // No backend in the scenario: auto, which says what it chose and why, in
  // the first lines and in meta. On a software EGL renderer (llvmpipe) or
  // none it is the CPU backend in float, its fast path; on a GPU it is gl.
  const std::string choice = j["meta"]["backend_choice"];
  EXPECT_NE(r.out.find("backend:  " + choice), std::string::npos) << r.out;
  const bool gpu = choice.find("hardware GPU") != std::string::npos;
  EXPECT_EQ(choice.rfind(gpu ? "auto chose gl (float): " : "auto chose cpu (float): ", 0), 0u) << choice;
  EXPECT_EQ(j["meta"]["backend"], gpu ? "gl" : "cpu");
  EXPECT_EQ(j["meta"]["precision"], "float");
  EXPECT_GT(j["meta"]["real_time_factor"].get<double>(), 0.0);
  EXPECT_NE(r.out.find("real time: "), std::string::npos) << r.out;
  EXPECT_EQ(j["meta"]["completed"], true);
  EXPECT_EQ(j["meta"]["mesh_kind"], "tet");
  // Tool bottom reaches the top face (z = 0.04) at t = 0.025 s and is 5 mm in at the end.
  EXPECT_GT(j["samples"]["force"][49][2].get<double>(), 0.0);
  EXPECT_EQ(j["samples"]["force"][10][2].get<double>(), 0.0);
}

TEST(RunCli, PrecisionOverrideReachesTheBackend) {
  const fs::path dir = test_dir("float");
  write_cube_mesh(dir);
  const fs::path scene = write_scenario(dir, nlohmann::json::object());
  const auto r = run_organsim("run '" + scene.string() + "' -o '" + (dir / "out").string() + "' --precision double", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  // Only the CPU backend computes in double: auto takes it and says why.
  EXPECT_EQ(j["meta"]["precision"], "double");
  EXPECT_EQ(j["meta"]["backend"], "cpu");
  EXPECT_EQ(j["meta"]["backend_choice"], "auto chose cpu (double): double precision asked, which only the CPU backend computes");
}

TEST(RunCli, BadScenarioExitsNonZeroNamingTheJsonPath) {
  const fs::path dir = test_dir("bad");
  write_cube_mesh(dir);
  const fs::path scene = write_scenario(dir, nlohmann::json::parse(R"({"time": {"dt": "fast"}})"));
  const auto r = run_organsim("run '" + scene.string() + "' -o '" + (dir / "out").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 4);  // ErrorKind::Scenario
  EXPECT_NE(r.err.find("scene.json: time.dt: expected a number, got a string"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "forces.json"));

  // A missing mesh names the file that is missing.
  const fs::path scene2 = write_scenario(dir, nlohmann::json::parse(R"({"mesh": {"tet": "nope.mesh"}})"));
  const auto r2 = run_organsim("run '" + scene2.string() + "'", dir);
  EXPECT_EQ(r2.exit_code, 3);  // ErrorKind::Input
  EXPECT_NE(r2.err.find("nope.mesh"), std::string::npos) << r2.err;

  // A fixed index past the mesh names the JSON path and the scenario.
  const fs::path scene3 = write_scenario(dir, nlohmann::json::parse(R"({"fixed": [{"indices": [3, 125]}]})"));
  const auto r3 = run_organsim("run '" + scene3.string() + "'", dir);
  EXPECT_EQ(r3.exit_code, 4);
  EXPECT_NE(r3.err.find("scene.json: fixed[0].indices[1]"), std::string::npos) << r3.err;
}

TEST(RunCli, PlanListsThePassesTheSceneNeedsAndNoMore) {
  const fs::path dir = test_dir("plan");
  write_cube_mesh(dir);
  // Lean scene: no volume (volume_modulus 0), no tool, no gravity.
  const fs::path lean = write_scenario(dir, nlohmann::json::parse(R"({"gravity": [0, 0, 0]})"));
  const auto r = run_organsim("run --plan '" + lean.string() + "' -o '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("125 points"), std::string::npos) << r.out;
  // The material as the rules read it: E 5000 Pa springs alone are a solid of nu 1/4.
  EXPECT_NE(r.out.find("material: density 1060 kg/m^3, rule springs + volume_modulus, E 5000 Pa, nu 0.25 ("),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("  - springs:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("  - integrate:"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("  - volume:"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("  - tool-contact:"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("  - gravity:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no volume pass"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no tool pass"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no gravity pass"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "out")) << "--plan must not run";

  // Full scene: every pass is there and nothing is listed as left out but the renderer.
  nlohmann::json full = kPushTool;
  full["material"] = {{"volume_modulus", 10000}};
  const fs::path scene = write_scenario(dir, full);
  const auto r2 = run_organsim("run --plan '" + scene.string() + "'", dir);
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  for (const char* pass : {"  - surface-contact:", "  - springs:", "  - volume:", "  - gravity:", "  - tool-contact:",
                           "  - integrate:"}) {
    EXPECT_NE(r2.out.find(pass), std::string::npos) << pass << "\n" << r2.out;
  }
  EXPECT_NE(r2.out.find("broad phase"), std::string::npos) << "the contact's broad phase is named\n" << r2.out;
  EXPECT_EQ(r2.out.find("no volume pass"), std::string::npos) << r2.out;
  EXPECT_EQ(r2.out.find("no tool pass"), std::string::npos) << r2.out;
}

TEST(RunCli, GlBackendRunsOrFailsLoudlyNeverFallsBackToCpu) {
  const fs::path dir = test_dir("gl");
  write_cube_mesh(dir);
  const fs::path scene = write_scenario(dir, nlohmann::json::object());
  const auto r = run_organsim("run '" + scene.string() + "' --backend gl -o '" + (dir / "out").string() + "'", dir);
  if (r.exit_code == 0) {
    const auto j = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
    EXPECT_EQ(j["meta"]["backend"], "gl");
    // Each blow-up check is a GPU sync and the GPU flags non-finite
    // positions every tick: full checks every 50 ticks by default.
    EXPECT_EQ(j["meta"]["stability"]["check_interval_ticks"], 50);
    // On the CPU every 10; --check-interval sets it on either.
    const auto cpu = run_organsim("run '" + scene.string() + "' --backend cpu -o '" + (dir / "cpu").string() + "'", dir);
    ASSERT_EQ(cpu.exit_code, 0) << cpu.err;
    EXPECT_EQ(nlohmann::json::parse(test::slurp(dir / "cpu" / "forces.json"))["meta"]["stability"]["check_interval_ticks"], 10);
    const auto set = run_organsim(
        "run '" + scene.string() + "' --backend gl --check-interval 7 -o '" + (dir / "set").string() + "'", dir);
    ASSERT_EQ(set.exit_code, 0) << set.err;
    EXPECT_EQ(nlohmann::json::parse(test::slurp(dir / "set" / "forces.json"))["meta"]["stability"]["check_interval_ticks"], 7);
  } else {
    test::expect_no_gl_context_here(r);
    EXPECT_FALSE(fs::exists(dir / "out" / "forces.json"));
  }
}

TEST(RunCli, BackendSwitchOnTheCommandLineTakesThatBackendsPrecision) {
  // liver_push.json asks for cpu in double; --backend gl must not inherit
  // "double" (which gl cannot do) but use gl's own float.
  const fs::path dir = test_dir("switch");
  const std::string scenario = std::string(ORGANSIM_SOURCE_DIR) + "/scenarios/liver_push.json";
  const auto r = run_organsim("run --plan '" + scenario + "' --backend gl", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("gl (float"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace run_cli_test
}  // namespace organsim
