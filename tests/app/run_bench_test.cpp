// `organsim bench` runs quickly with small options and reports what it measured
// (speed itself is never asserted: that is what the command is for).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <thread>

#include "core/sim/cpu_kernel_simd.h"
#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace run_bench_test {
namespace {

namespace fs = std::filesystem;

TEST(RunBench, QuickJsonRunHasOneRowPerSizeAndConfigurationWithThePaperFigures) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench";
  const auto r = test::run_organsim(
      "bench --sizes 300,1617 --backend cpu --precision double --repetitions 3 --steps 5 --warmup 2 --no-exude --json -", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  // A row per size and SIMD target this CPU runs, best first, side by side.
  const std::vector<SimdTarget> targets = simd_targets_supported();
  ASSERT_EQ(j["rows"].size(), 2 * targets.size());
  for (size_t i = 0; i < j["rows"].size(); ++i) {
    const auto& row = j["rows"][i];
    const std::string kernel = targets[i % targets.size()].name;
    EXPECT_EQ(row["kernel"], kernel);
    EXPECT_NE(row["device"].get<std::string>().find("simd (" + kernel + ") kernel"), std::string::npos) << row.dump();
    EXPECT_EQ(row["points"], j["rows"][i - i % targets.size()]["points"]);  // one mesh per size
  }
  EXPECT_EQ(j["machine"]["logical_cpus"].get<int>() > 0, true);
  EXPECT_EQ(j["settings"]["repetitions"], 3);
  for (const auto& row : j["rows"]) {
    EXPECT_EQ(row["backend"], "cpu");
    EXPECT_EQ(row["precision"], "double");
    const double med = row["median_ms"], lo = row["min_ms"], hi = row["max_ms"];
    EXPECT_GT(lo, 0.0);
    EXPECT_LE(lo, med);
    EXPECT_LE(med, hi);
    // The plain scatter step is timed in the same run and the ratio printed.
    const double scatter = row["scatter_median_ms"];
    EXPECT_GT(scatter, 0.0);
    EXPECT_DOUBLE_EQ(row["speedup_over_scatter"].get<double>(), scatter / med);
    // The thread count and the kernel are reported with how they were chosen.
    const std::string device = row["device"];
    EXPECT_NE(device.find("kernel"), std::string::npos) << device;
  }
  // Meshed within 10 % of the asked point count (the mesher's promise).
  const auto& second_size = j["rows"][targets.size()];
  EXPECT_NEAR(second_size["points"].get<double>(), 1617, 162);
  // The paper's Table 1 sits next to its size, and only there.
  EXPECT_FALSE(j["rows"][0].contains("paper"));
  EXPECT_EQ(second_size["paper"]["model"], "Bunny5");
  EXPECT_DOUBLE_EQ(second_size["paper"]["xeon_3ghz_ms"].get<double>(), 0.99);
}

// The CPU model as /proc/cpuinfo names it (what the file must record).
std::string cpu_model_name() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown CPU";
}

// " WORD ": a whole field of a table line.
std::string field(const std::string& word) {
  std::string s(" ");
  s += word;
  s += ' ';
  return s;
}

std::string fixed4(double v) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(4) << v;
  return s.str();
}

// `--json FILE` prints the table as usual and writes the same run's figures
// to FILE: the data files under docs/bench/ are made this way.
TEST(RunBench, JsonFileHoldsTheFiguresOfTheTablePrintedInTheSameRun) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_json_file";
  fs::remove_all(dir);
  const fs::path file = dir / "bench.json";
  const std::string best = simd_targets_supported().front().name;
  const auto r = test::run_organsim("bench --sizes 300 --backend cpu --precision double,float --simd " + best +
                                        " --repetitions 3 --steps 5 --warmup 2 --no-exude --no-frames --json " +
                                        file.string(),
                                    dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(file)) << r.out;
  const auto j = nlohmann::json::parse(test::slurp(file));  // throws (and fails) unless it is whole JSON

  // What was asked is what the file says was run.
  EXPECT_EQ(j["settings"]["sizes"], nlohmann::json::array({300}));
  EXPECT_EQ(j["settings"]["repetitions"], 3);
  EXPECT_EQ(j["settings"]["steps_per_repetition"], 5);
  EXPECT_EQ(j["settings"]["warmup_steps"], 2);
  EXPECT_EQ(j["settings"]["exude"], false);
  EXPECT_EQ(j["machine"]["cpu"], cpu_model_name());
  EXPECT_NE(r.out.find("machine: " + j["machine"]["cpu"].get<std::string>()), std::string::npos) << r.out;
  EXPECT_TRUE(j["frames"].empty());

  // One row per precision, each the row the table printed: its counts and
  // its median (the table rounds to 4 decimals) on one line of stdout.
  ASSERT_EQ(j["rows"].size(), 2u);
  EXPECT_EQ(j["rows"][0]["precision"], "double");
  EXPECT_EQ(j["rows"][1]["precision"], "float");
  for (const auto& row : j["rows"]) {
    EXPECT_EQ(row["backend"], "cpu");
    const double med = row["median_ms"];
    std::istringstream lines(r.out);
    std::string line;
    bool printed = false;
    while (std::getline(lines, line)) {
      if (line.find(" cpu     " + row["precision"].get<std::string>()) == std::string::npos) continue;
      if (line.find(field(best)) == std::string::npos) continue;
      if (line.find(field(std::to_string(row["points"].get<int>()))) == std::string::npos) continue;
      if (line.find(field(std::to_string(row["tets"].get<int>()))) == std::string::npos) continue;
      if (line.find(field(fixed4(med))) != std::string::npos) printed = true;
    }
    EXPECT_TRUE(printed) << "no table line with " << row.dump() << "\n" << r.out;
    EXPECT_DOUBLE_EQ(row["speedup_over_scatter"].get<double>(), row["scatter_median_ms"].get<double>() / med);
  }
  // The mesh the progress line reported is the one timed.
  EXPECT_NE(r.err.find(field(std::to_string(j["rows"][0]["points"].get<int>())) + "meshed"), std::string::npos)
      << r.err;
  // Nothing else left in the folder: no temporary beside the file.
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    EXPECT_TRUE(name == "bench.json" || name == "stdout.txt" || name == "stderr.txt") << name;
  }
}

TEST(RunBench, AJsonFileThatCannotBeWrittenIsAnOutputErrorNamingIt) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_json_bad";
  const fs::path file = dir / "no_such_folder" / "bench.json";
  const auto r = test::run_organsim("bench --sizes 300 --backend cpu --precision float --repetitions 1 --steps 2 "
                                    "--warmup 0 --no-exude --no-frames --json " + file.string(), dir);
  EXPECT_EQ(r.exit_code, 7) << r.err;
  EXPECT_NE(r.err.find(file.string()), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file));
}

TEST(RunBench, ABackendAskedForByNameRunsOrIsAnErrorNeverACpuRow) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_gl";
  const auto r = test::run_organsim("bench --sizes 300 --backend gl --repetitions 1 --steps 2 --warmup 0 --no-exude --json -", dir);
  if (r.exit_code == 0) {
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["rows"].size(), 1u);
    EXPECT_EQ(j["rows"][0]["backend"], "gl");
  } else {
    test::expect_no_gl_context_here(r);  // never a quiet CPU row, never a broken backend
  }
}

// ORGANSIM_SIMD set (or, with nullptr, unset) for the organsim processes a
// test starts, and put back as it was when the scope ends.
class ScopedSimdVariable {
 public:
  explicit ScopedSimdVariable(const char* value) {
    if (const char* old = std::getenv("ORGANSIM_SIMD")) old_ = old;
    if (value)
      setenv("ORGANSIM_SIMD", value, 1);
    else
      unsetenv("ORGANSIM_SIMD");
  }
  ~ScopedSimdVariable() {
    if (old_)
      setenv("ORGANSIM_SIMD", old_->c_str(), 1);
    else
      unsetenv("ORGANSIM_SIMD");
  }

 private:
  std::optional<std::string> old_;
};

// The targets of `bench --materials`' three ratios, as docs/bench.md states
// them ("Materials side by side"): written here, not read from the output.
struct RatioTarget {
  const char* of;
  const char* over;
  double target;
};
constexpr RatioTarget kMaterialRatioTargets[] = {
    {"nu_0.45", "volume_modulus", 1.3}, {"nu_0.2", "volume_modulus", 2.0}, {"sutured", "unsutured", 1.1}};

// `bench --materials`: the five rows side by side, each with the kernel it
// ran on, and the three ratios of their medians, each with its target and
// verdict against the targets above, in the JSON file and on the table
// printed in the same run. (The ratios' values are timings, what the
// command is for, and are not asserted.)
TEST(RunBench, MaterialComparisonReportsEveryRowWithItsKernelAndTheRatios) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_materials";
  fs::remove_all(dir);
  const fs::path scenario = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "liver_suture.json";
  const fs::path file = dir / "materials.json";
  const ScopedSimdVariable best_target(nullptr);  // the CPU's best target, whatever the environment says
  const auto r = test::run_organsim("bench --materials --sizes 300 --repetitions 2 --steps 3 --warmup 1 --no-exude "
                                    "--materials-scenario '" + scenario.string() + "' --json '" + file.string() + "'",
                                    dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::slurp(file));
  EXPECT_TRUE(j["rows"].empty());  // the comparison instead of the size table
  ASSERT_EQ(j["materials"].size(), 1u);
  const auto& c = j["materials"][0];
  EXPECT_EQ(c["precision"], "float");  // the default: the fast path, as in the figures
  ASSERT_EQ(c["rows"].size(), 5u);
  const char* names[] = {"volume_modulus", "nu_0.45", "nu_0.2", "unsutured", "sutured"};
  std::map<std::string, double> median;
  for (size_t i = 0; i < 5; ++i) {
    const auto& row = c["rows"][i];
    EXPECT_EQ(row["name"], names[i]);
    const std::string kernel = row["kernel"], device = row["device"];
    // The kernel is the one the backend's device line names after the
    // timing: the simd kernel on this CPU's best target, every material.
    EXPECT_EQ(kernel, "simd (" + simd_targets_supported().front().name + ")") << device;
    EXPECT_NE(device.find(", " + kernel + " kernel"), std::string::npos) << device;
    // Every row on the same, fixed thread count (no per-row timing choice).
    EXPECT_NE(device.find(std::to_string(std::max(1u, std::thread::hardware_concurrency())) + " thread"),
              std::string::npos) << device;
    EXPECT_NEAR(row["points"].get<double>(), 300, 60) << row.dump();
    const double lo = row["min_ms"], med = row["median_ms"], hi = row["max_ms"];
    EXPECT_GT(lo, 0.0);
    EXPECT_LE(lo, med);
    EXPECT_LE(med, hi);
    median[names[i]] = med;
  }
  // The material rows share one mesh; the suture rows are one model with and
  // without its sutures (the same points, the sutures' springs added).
  EXPECT_EQ(c["rows"][0]["points"], c["rows"][2]["points"]);
  EXPECT_EQ(c["rows"][3]["sutures"], 0);
  EXPECT_GT(c["rows"][4]["sutures"].get<int>(), 0);
  EXPECT_EQ(c["rows"][3]["points"], c["rows"][4]["points"]);
  EXPECT_EQ(c["rows"][4]["springs"].get<int>(),
            c["rows"][3]["springs"].get<int>() + c["rows"][4]["sutures"].get<int>());
  // Each row's step has its material's passes.
  auto has_pass = [&](size_t row, const std::string& pass) {
    const auto& p = c["rows"][row]["passes"];
    return std::find(p.begin(), p.end(), pass) != p.end();
  };
  EXPECT_FALSE(has_pass(0, "nodal-pressure"));
  EXPECT_TRUE(has_pass(1, "nodal-pressure"));
  EXPECT_TRUE(has_pass(2, "shear-element"));
  ASSERT_EQ(c["ratios"].size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const RatioTarget& expected = kMaterialRatioTargets[i];
    const auto& ratio = c["ratios"][i];
    EXPECT_EQ(ratio["of"], expected.of);
    EXPECT_EQ(ratio["over"], expected.over);
    EXPECT_EQ(ratio["name"], std::string(expected.of) + " / " + expected.over);
    EXPECT_EQ(ratio["target"].get<double>(), expected.target) << ratio.dump();
    // The ratio is of these two rows' medians (a ratio of other rows, or of
    // their means, differs), and its verdict is against the stated target.
    const double value = ratio["ratio"];
    EXPECT_DOUBLE_EQ(value, median[expected.of] / median[expected.over]);
    EXPECT_EQ(ratio["within_target"].get<bool>(), value <= expected.target) << ratio.dump();
    // The table line: "  nu_0.45 / volume_modulus     1.67x  (target 1.3x: not met)".
    char line[160];
    std::snprintf(line, sizeof line, "%.2fx  (target %.1fx: %s)", value, expected.target,
                  value <= expected.target ? "met" : "not met");
    const size_t at = r.out.find(std::string("  ") + expected.of + " / " + expected.over + " ");
    ASSERT_NE(at, std::string::npos) << r.out;
    const std::string printed = r.out.substr(at, r.out.find('\n', at) - at);
    EXPECT_NE(printed.find(line), std::string::npos) << printed << "\nexpected: " << line;
  }
}

// ORGANSIM_SIMD picks the target every row runs on: with the portable
// fallback ("scalar", compiled on every architecture) asked for, each of the
// five rows names exactly that kernel.
TEST(RunBench, MaterialComparisonRunsEveryRowOnTheTargetOrganSimSimdNames) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_materials_scalar";
  const fs::path scenario = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "liver_suture.json";
  const ScopedSimdVariable scalar("scalar");
  const auto r = test::run_organsim("bench --materials --sizes 300 --repetitions 1 --steps 1 --warmup 0 --no-exude "
                                    "--materials-scenario '" + scenario.string() + "' --json -", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto c = nlohmann::json::parse(r.out)["materials"].at(0);
  ASSERT_EQ(c["rows"].size(), 5u);
  for (const auto& row : c["rows"]) {
    EXPECT_EQ(row["kernel"], "simd (scalar)") << row.dump();
    EXPECT_NE(row["device"].get<std::string>().find(", simd (scalar) kernel"), std::string::npos) << row.dump();
  }
}

// On the GL backend the same five rows, each on the GL device, with the
// material's passes (llvmpipe here, a GPU where there is one).
TEST(RunBench, MaterialComparisonRunsOnTheGlBackend) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_materials_gl";
  const fs::path scenario = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "liver_suture.json";
  const auto r = test::run_organsim("bench --materials --backend gl --sizes 300 --repetitions 1 --steps 2 --warmup 0 "
                                    "--no-exude --materials-scenario '" + scenario.string() + "' --json -", dir);
  if (r.exit_code != 0) {
    test::expect_no_gl_context_here(r);  // never a quiet CPU row, never a broken backend
    return;
  }
  const auto c = nlohmann::json::parse(r.out)["materials"].at(0);
  EXPECT_EQ(c["backend"], "gl");
  ASSERT_EQ(c["rows"].size(), 5u);
  for (const auto& row : c["rows"]) {
    EXPECT_EQ(row["kernel"], "glsl") << row.dump();
    EXPECT_NE(row["device"].get<std::string>().find("invocation(s) per point"), std::string::npos) << row.dump();
  }
  const auto& shear = c["rows"][2]["passes"];
  EXPECT_NE(std::find(shear.begin(), shear.end(), "shear-element"), shear.end()) << shear.dump();
  EXPECT_EQ(c["rows"][4]["springs"].get<int>(),
            c["rows"][3]["springs"].get<int>() + c["rows"][4]["sutures"].get<int>());
}

TEST(RunBench, MaterialComparisonRefusesTwoBackendsAndAScenarioWithoutSutures) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_materials_bad";
  const auto two = test::run_organsim("bench --materials --sizes 300 --backend cpu,gl --json -", dir);
  EXPECT_EQ(two.exit_code, 2) << two.err;
  EXPECT_NE(two.err.find("--materials times one backend"), std::string::npos) << two.err;
  const fs::path push = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "liver_push.json";
  const auto none = test::run_organsim("bench --materials --sizes 300 --repetitions 1 --steps 1 --warmup 0 --no-exude "
                                       "--materials-scenario '" + push.string() + "' --json -", dir);
  EXPECT_EQ(none.exit_code, 4) << none.err;
  EXPECT_NE(none.err.find(push.string() + ": events"), std::string::npos) << none.err;
}

// The aims of `bench --implicit` (docs/integrators.md, "Measured"): written
// here, not read from the output.
struct ImplicitAim {
  const char* name;
  double target;
};
constexpr ImplicitAim kImplicitAims[] = {{"cg_iteration / verlet_step", 1.5},
                                         {"cg_iterations_8kPa", 30},
                                         {"implicit_1MPa / verlet_1MPa", 1.0 / 3},
                                         {"two_level_1MPa / verlet_1MPa", 1.0 / 3},
                                         {"simd_product / scalar_product", 1}};

// `bench --implicit`: the seven rows side by side, Verlet at the model's
// guaranteed step on the simd kernel, implicit Euler at 1 ms on the
// implicit solve's threads (its products on the kernel's SIMD target, and
// once on the scalar gather) and implicit damping within its undamped
// limit, the implicit rows with their CG iterations and cost per
// iteration, and the five aims computed from the rows they name.
// (Timings are what the command is for and are not asserted; that the
// stiff liver needs more CG iterations than the soft one at the same step is
// the physics: its system's condition number grows with h^2 K / M.)
TEST(RunBench, ImplicitComparisonReportsBothIntegratorsWithTheirSolves) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_implicit";
  fs::remove_all(dir);
  const fs::path file = dir / "implicit.json";
  const auto r = test::run_organsim("bench --implicit --sizes 300 --repetitions 2 --steps 10 --warmup 10 --threads 2 "
                                    "--no-exude --json '" + file.string() + "'",
                                    dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::slurp(file));
  EXPECT_TRUE(j["rows"].empty());  // the comparison instead of the size table
  ASSERT_EQ(j["implicit"].size(), 1u);
  const auto& c = j["implicit"][0];
  ASSERT_EQ(c["rows"].size(), 7u);
  const char* names[] = {"verlet_8kPa",  "implicit_8kPa",  "verlet_1MPa", "implicit_1MPa",
                         "damping_1MPa", "two_level_1MPa", "scalar_8kPa"};
  const std::string product = "simd (" + simd_targets_supported().front().name + ") product";
  for (size_t i = 0; i < 7; ++i) {
    const auto& row = c["rows"][i];
    SCOPED_TRACE(row.dump());
    EXPECT_EQ(row["name"], names[i]);
    EXPECT_NEAR(row["points"].get<double>(), 300, 60);
    EXPECT_GT(row["fixed"].get<int>(), 0);
    EXPECT_LT(row["fixed"].get<int>(), row["points"].get<int>() / 2);
    const std::string device = row["device"];
    const double dt = row["dt"], dt_crit = row["dt_crit"], median = row["median_ms"];
    EXPECT_NE(device.find("2 threads"), std::string::npos);
    EXPECT_NEAR(row["ms_per_simulated_ms"].get<double>(), median / (1e3 * dt), 1e-12 * median / dt);
    if (i == 4) {
      // Implicit damping: the largest step dividing 1 ms within the undamped
      // limit 2/omega_max, which lies between dt_crit and 1 ms here.
      EXPECT_EQ(row["integrator"], "implicit_damping");
      EXPECT_NE(device.find("implicit damping"), std::string::npos);
      const double substeps = 1e-3 / dt;
      EXPECT_NEAR(substeps, std::round(substeps), 1e-9);
      EXPECT_GT(dt, dt_crit);
      EXPECT_LT(dt, 1e-3);
      EXPECT_GE(row["cg_iterations_median"].get<double>(), 1);
    } else if (i % 2 == 0 && i < 5) {
      EXPECT_EQ(row["integrator"], "verlet");
      EXPECT_NE(device.find("simd ("), std::string::npos);
      EXPECT_GT(dt, 0.5 * dt_crit);  // the guaranteed step, not a fraction of it
      EXPECT_LE(dt, dt_crit);
      EXPECT_EQ(row["cg_iterations_median"].get<double>(), 0);
    } else {
      EXPECT_EQ(row["integrator"], "implicit_euler");
      EXPECT_NE(device.find("implicit Euler"), std::string::npos);
      EXPECT_EQ(dt, 1e-3);
      if (i == 3 || i == 5) {
        EXPECT_GT(dt, 10 * dt_crit);  // far beyond what Verlet could step
      }
      EXPECT_NE(device.find(i == 5 ? "two_level-preconditioned" : "block_jacobi-preconditioned"), std::string::npos);
      EXPECT_NE(device.find(i == 6 ? std::string("(reference, double") : product), std::string::npos);
      EXPECT_GE(row["cg_iterations_median"].get<double>(), 1);
      EXPECT_GT(row["cg_ms_per_iteration"].get<double>(), 0);
      EXPECT_LT(row["cg_ms_per_iteration"].get<double>(), median);
    }
  }
  const auto& rows = c["rows"];
  EXPECT_EQ(rows[0]["dt_crit"], rows[1]["dt_crit"]);
  EXPECT_LT(rows[2]["dt_crit"].get<double>(), 0.2 * rows[0]["dt_crit"].get<double>());
  EXPECT_GT(rows[3]["cg_iterations_median"].get<double>(), rows[1]["cg_iterations_median"].get<double>());
  // The coarse correction takes out the stiff liver's smooth error: fewer iterations than block Jacobi alone.
  EXPECT_LT(rows[5]["cg_iterations_median"].get<double>(), rows[3]["cg_iterations_median"].get<double>());
  const double values[] = {rows[1]["cg_ms_per_iteration"].get<double>() / rows[0]["median_ms"].get<double>(),
                           rows[1]["cg_iterations_median"].get<double>(),
                           rows[3]["ms_per_simulated_ms"].get<double>() / rows[2]["ms_per_simulated_ms"].get<double>(),
                           rows[5]["ms_per_simulated_ms"].get<double>() / rows[2]["ms_per_simulated_ms"].get<double>(),
                           rows[1]["cg_ms_per_iteration"].get<double>() / rows[6]["cg_ms_per_iteration"].get<double>()};
  ASSERT_EQ(c["ratios"].size(), 5u);
  for (size_t i = 0; i < 5; ++i) {
    const auto& ratio = c["ratios"][i];
    EXPECT_EQ(ratio["name"], kImplicitAims[i].name);
    EXPECT_DOUBLE_EQ(ratio["target"].get<double>(), kImplicitAims[i].target);
    EXPECT_DOUBLE_EQ(ratio["value"].get<double>(), values[i]) << ratio.dump();
    EXPECT_EQ(ratio["within_target"].get<bool>(), values[i] <= kImplicitAims[i].target);
    EXPECT_NE(r.out.find(kImplicitAims[i].name), std::string::npos) << r.out;
  }
}

TEST(RunBench, ImplicitAndMaterialComparisonsAreOneAtATime) {
  const auto r = test::run_organsim("bench --implicit --materials --sizes 300", fs::path(ORGANSIM_TEST_TMP));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--implicit and --materials"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace run_bench_test
}  // namespace organsim
