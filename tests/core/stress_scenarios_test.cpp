// The stress suite (scenarios/stress/, small 125-point boxes): each case runs
// through the real CLI and ends as stated in its description: stable and
// bounded, or a clean refusal or stop with the named error and exit code.
// No case may leave a NaN (JSON null) or a non-number in its force log.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace stress_scenarios_test {
namespace {

namespace fs = std::filesystem;

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

CliResult organsim(const std::string& args) {
  const std::string cmd = std::string(ORGANSIM_EXE) + " " + args + " 2>&1";
  CliResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) r.output.append(buf, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string scenario(const std::string& name) {
  return std::string(ORGANSIM_SOURCE_DIR) + "/scenarios/stress/" + name + ".json";
}

fs::path outdir(const std::string& name) { return fs::path(ORGANSIM_TEST_TMP) / "stress" / name; }

// Runs a case; returns the CLI result and (if written) the parsed force log.
CliResult run_case(const std::string& name, const std::string& extra = "") {
  fs::remove_all(outdir(name));
  return organsim("run " + scenario(name) + " -o " + outdir(name).string() + " " + extra);
}

nlohmann::json force_log(const std::string& name) {
  std::ifstream in(outdir(name) / "forces.json");
  if (!in) return nullptr;
  return nlohmann::json::parse(in);
}

// Every force, torque and tool position entry is a finite number; returns the peak |F|.
double expect_all_finite(const nlohmann::json& log) {
  double peak = 0;
  for (const char* column : {"force", "torque", "tool_position"})
    for (const auto& v : log["samples"][column]) {
      EXPECT_EQ(v.size(), 3u);
      double n2 = 0;
      for (const auto& c : v) {
        EXPECT_TRUE(c.is_number()) << column << " has " << c.dump();
        if (c.is_number()) n2 += c.get<double>() * c.get<double>();
      }
      if (std::string(column) == "force") peak = std::max(peak, std::sqrt(n2));
    }
  for (const auto& t : log["samples"]["t"]) EXPECT_TRUE(t.is_number());
  return peak;
}

constexpr int kNumerical = 5, kScenario = 4, kInput = 3;

TEST(StressScenarios, StiffSpringsRefusedWithStableSuggestion) {
  const CliResult r = run_case("stiff_x1000");
  EXPECT_EQ(r.exit_code, kNumerical) << r.output;
  EXPECT_NE(r.output.find("exceeds the critical step dt_crit"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("time.substeps = "), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(outdir("stiff_x1000") / "forces.json"));  // refused before running
}

TEST(StressScenarios, JustUnderCriticalStepIsStable) {
  const CliResult r = run_case("dt_under");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto log = force_log("dt_under");
  EXPECT_TRUE(log["meta"]["completed"].get<bool>());
  expect_all_finite(log);
  // The predicted dt_crit is in the log and the step is below it.
  EXPECT_LT(log["meta"]["dt"].get<double>(), log["meta"]["dt_crit"].get<double>());
}

TEST(StressScenarios, JustOverCriticalStepIsRefused) {
  const CliResult r = run_case("dt_over");
  EXPECT_EQ(r.exit_code, kNumerical) << r.output;
  EXPECT_NE(r.output.find("--allow-unstable"), std::string::npos) << r.output;
}

// Far over, forced: the blow-up check stops the run before any NaN, and the
// log is valid JSON saying why, with the samples up to the stop.
TEST(StressScenarios, FarOverCriticalStepIsStoppedCleanly) {
  const CliResult r = run_case("dt_far_over", "--allow-unstable");
  EXPECT_EQ(r.exit_code, kNumerical) << r.output;
  EXPECT_NE(r.output.find("warning:"), std::string::npos) << r.output;
  const auto log = force_log("dt_far_over");
  ASSERT_FALSE(log.is_null());
  EXPECT_FALSE(log["meta"]["completed"].get<bool>());
  const std::string reason = log["meta"]["stop_reason"].get<std::string>();
  EXPECT_NE(reason.find("run stopped at t = "), std::string::npos) << reason;
  EXPECT_NE(reason.find("(input numbering)"), std::string::npos) << reason;
  EXPECT_NE(reason.find("exceeds dt_crit"), std::string::npos) << reason;
  EXPECT_LT(log["samples"]["t"].size(), 200u);  // cut short (200 ticks asked)
  expect_all_finite(log);
}

// 50 % compression: completes; the reaction is bounded by the elastic estimate
// E A strain = 5 kPa * 16 cm^2 * 0.5 = 4 N within a factor 3 (lattice
// stiffness and the volume term add to E; a blow-up would be far beyond).
TEST(StressScenarios, HalfCompressionIsStableAndBounded) {
  const CliResult r = run_case("compress_50");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto log = force_log("compress_50");
  EXPECT_TRUE(log["meta"]["completed"].get<bool>());
  const double peak = expect_all_finite(log);
  EXPECT_GT(peak, 4.0 / 3);
  EXPECT_LT(peak, 4.0 * 3);
}

// The tool through the whole box: the penalty contact lets the material close
// behind the sphere, so the run completes with a bounded force (under 100 N,
// ~6x the observed 16 N) and no NaN.
TEST(StressScenarios, ToolThroughTheOrganCompletesBounded) {
  const CliResult r = run_case("tool_through");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto log = force_log("tool_through");
  EXPECT_TRUE(log["meta"]["completed"].get<bool>());
  const double peak = expect_all_finite(log);
  EXPECT_GT(peak, 0.1);  // it did touch
  EXPECT_LT(peak, 100.0);
}

TEST(StressScenarios, InvertedTetRejectedAtLoad) {
  const CliResult r = run_case("inverted_tets");
  EXPECT_EQ(r.exit_code, kInput) << r.output;
  EXPECT_NE(r.output.find("inverted"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("inverted.mesh"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(outdir("inverted_tets") / "forces.json"));
}

TEST(StressScenarios, CoincidentPointsStable) {
  const CliResult r = run_case("coincident_points");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto log = force_log("coincident_points");
  EXPECT_TRUE(log["meta"]["completed"].get<bool>());
  EXPECT_EQ(log["meta"]["points"].get<int>(), 250);  // duplicates kept apart, not merged
  expect_all_finite(log);
}

// A near-flat tet passes the loader's zero-volume test but its volume term
// limits dt_crit: refused at the default step; --plan names the sliver
// (interior point 31 moved 0.99 of a cell) and its quality.
TEST(StressScenarios, NearZeroVolumeTetLimitsTheStep) {
  const CliResult r = run_case("near_zero_volume");
  EXPECT_EQ(r.exit_code, kNumerical) << r.output;
  const CliResult plan = organsim("run --plan " + scenario("near_zero_volume"));
  ASSERT_EQ(plan.exit_code, 0) << plan.output;
  EXPECT_NE(plan.output.find("limiting points (input numbering): 3"), std::string::npos) << plan.output;
  EXPECT_NE(plan.output.find(", 31"), std::string::npos) << plan.output;
  EXPECT_NE(plan.output.find("quality 0.00"), std::string::npos) << plan.output;
}

TEST(StressScenarios, ZeroAndNegativeDensityRejected) {
  for (const char* name : {"zero_density", "negative_density"}) {
    const CliResult r = run_case(name);
    EXPECT_EQ(r.exit_code, kScenario) << r.output;
    EXPECT_NE(r.output.find("material.density"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(outdir(name) / "forces.json"));
  }
}

// Very high damping: dt_crit shrinks below the undamped 2/omega_max, the
// chosen dt is under it, and the run completes.
TEST(StressScenarios, HighDampingStable) {
  const CliResult r = run_case("high_damping");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto log = force_log("high_damping");
  EXPECT_TRUE(log["meta"]["completed"].get<bool>());
  const auto& st = log["meta"]["stability"];
  EXPECT_LT(st["dt_crit"].get<double>(), 0.5 * st["dt_crit_undamped"].get<double>());
  expect_all_finite(log);
}

}  // namespace
}  // namespace stress_scenarios_test
