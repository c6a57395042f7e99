// `organsim run` with time.integrator "implicit_euler" end to end on a small
// tet mesh: --plan's passes, the products' SIMD target and dt against dt_crit, a dt far beyond dt_crit
// run and logged with its CG statistics, a CG that cannot converge turned
// into exit code 9 with the force log whole, and the backends that do not
// integrate implicitly refused.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/mesh/mesh_io.h"
#include "core/mesh/tet_mesh.h"
#include "core/sim/cpu_kernel_simd.h"
#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace run_implicit_cli_test {
namespace {

namespace fs = std::filesystem;
using test::run_organsim;

// A stiff 4 cm cube (E = 1 MPa: dt_crit ~ 0.02 ms) pressed by a sphere,
// stepped implicitly at 1 ms, one step per tick; `extra` merged over it.
fs::path implicit_scene(const std::string& name, const nlohmann::json& extra) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_implicit" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_tet_mesh(dir / "cube.mesh", make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.04, 0.04, 0.04), 4, 4, 4));
  nlohmann::json j = nlohmann::json::parse(R"({
    "mesh": {"tet": "cube.mesh"},
    "material": {"young_modulus": 1e6, "poisson_ratio": 0.45},
    "fixed": [{"plane": {"point": [0, 0, 0.001], "normal": [0, 0, -1]}}],
    "time": {"duration": 0.1, "dt": 0.001, "substeps": 1, "integrator": "implicit_euler"},
    "tool": {"radius": 0.01, "contact_stiffness": 2000,
             "keyframes": [{"t": 0, "position": [0.02, 0.02, 0.0505]}, {"t": 0.1, "position": [0.02, 0.02, 0.048]}]}
  })");
  j.merge_patch(extra);
  std::ofstream(dir / "scene.json") << j.dump(2);
  return dir;
}

TEST(RunImplicitCli, PlanListsTheIntegratorsPassesAndHowManyDtCritTheStepSpans) {
  const fs::path dir = implicit_scene("plan", nlohmann::json::object());
  const auto r = run_organsim("run --plan '" + (dir / "scene.json").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* pass : {"  - linearise:", "  - conjugate-gradient:", "  - velocity-update:"})
    EXPECT_NE(r.out.find(pass), std::string::npos) << pass << "\n" << r.out;
  EXPECT_EQ(r.out.find("  - integrate:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("x dt_crit: implicit Euler, not bounded by dt_crit"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("UNSTABLE"), std::string::npos) << r.out;
  // The products gather on the kernel's best target, or on the one ORGANSIM_SIMD names.
  const std::string best = "implicit Euler (simd (" + simd_targets_supported().front().name + ") product, double;";
  EXPECT_NE(r.out.find(best), std::string::npos) << r.out;
  const std::string lowest = simd_targets_supported().back().name;
  setenv("ORGANSIM_SIMD", lowest.c_str(), 1);
  const auto forced = run_organsim("run --plan '" + (dir / "scene.json").string() + "'", dir);
  unsetenv("ORGANSIM_SIMD");
  ASSERT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_NE(forced.out.find("matrix-free products (simd (" + lowest + ") product)"), std::string::npos) << forced.out;
}

TEST(RunImplicitCli, AStepFarBeyondDtCritRunsAndLogsItsSolves) {
  const fs::path dir = implicit_scene("run", nlohmann::json::object());
  const auto r = run_organsim("run '" + (dir / "scene.json").string() + "' -o '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("implicit: CG iterations per step median"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  ASSERT_TRUE(j["meta"]["completed"].get<bool>());
  const auto& i = j["meta"]["integrator"];
  EXPECT_EQ(i["name"], "implicit_euler");
  EXPECT_EQ(i["steps"], 100);
  EXPECT_EQ(i["cg_unconverged_steps"], 0);
  EXPECT_GT(i["cg_iterations_max"].get<int>(), 0);
  EXPECT_LE(i["cg_residual_max"].get<double>(), 1e-5);
  EXPECT_GT(j["meta"]["dt"].get<double>() / j["meta"]["dt_crit"].get<double>(), 10);
  // The tool pressed the cube: its last force points up and is finite.
  const auto& last = j["samples"]["force"].back();
  EXPECT_GT(last[2].get<double>(), 0);
}

TEST(RunImplicitCli, ACgThatCannotConvergeEndsWithTheWarningCodeAndAWholeLog) {
  const fs::path dir = implicit_scene("limit", nlohmann::json::parse(R"({"time": {"cg_tolerance": 0, "cg_max_iterations": 2}})"));
  const auto r = run_organsim("run '" + (dir / "scene.json").string() + "' -o '" + (dir / "out").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 9) << r.err;
  EXPECT_NE(r.err.find("organsim: warning: implicit Euler: the conjugate gradients stopped at cg_max_iterations = 2"),
            std::string::npos)
      << r.err;
  const auto j = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  EXPECT_TRUE(j["meta"]["completed"].get<bool>());
  EXPECT_EQ(j["meta"]["integrator"]["cg_unconverged_steps"], 100);
}

TEST(RunImplicitCli, BackendsThatIntegrateOnlyExplicitlyAreRefused) {
  const fs::path dir = implicit_scene("refused", nlohmann::json::object());
  const auto gl = run_organsim("run --plan '" + (dir / "scene.json").string() + "' --backend gl", dir);
  EXPECT_EQ(gl.exit_code, 2) << gl.err;
  EXPECT_NE(gl.err.find("implicit_euler runs on the cpu backend only"), std::string::npos) << gl.err;
  const auto f = run_organsim("run --plan '" + (dir / "scene.json").string() + "' --backend cpu --precision float", dir);
  EXPECT_EQ(f.exit_code, 2) << f.err;
  EXPECT_NE(f.err.find("double precision only"), std::string::npos) << f.err;
}

// fit runs Verlet only: an implicit scenario is refused, not fitted as Verlet.
TEST(RunImplicitCli, FitRefusesAnImplicitScenario) {
  const fs::path dir = implicit_scene("fit", nlohmann::json::object());
  std::ofstream(dir / "curve.csv") << "t,force\n0.05,0.1\n0.1,0.3\n";
  const auto fit = run_organsim("fit '" + (dir / "scene.json").string() + "' --measured '" +
                                    (dir / "curve.csv").string() + "' --param material.young_modulus -o '" +
                                    (dir / "fit").string() + "'", dir);
  EXPECT_EQ(fit.exit_code, 2) << fit.err;
  EXPECT_NE(fit.err.find("organsim fit simulates with Verlet only"), std::string::npos) << fit.err;
}

}  // namespace
}  // namespace run_implicit_cli_test
}  // namespace organsim
