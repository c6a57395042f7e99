// `organsim bench` runs quickly with small options and reports what it measured
// (speed itself is never asserted: that is what the command is for).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace {

namespace fs = std::filesystem;

TEST(RunBench, QuickJsonRunHasOneRowPerSizeAndConfigurationWithThePaperFigures) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench";
  const auto r = test::run_organsim(
      "bench --sizes 300,1617 --backend cpu --precision double --repetitions 3 --steps 5 --warmup 2 --no-exude --json", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["rows"].size(), 2u);
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
  EXPECT_NEAR(j["rows"][1]["points"].get<double>(), 1617, 162);
  // The paper's Table 1 sits next to its size, and only there.
  EXPECT_FALSE(j["rows"][0].contains("paper"));
  EXPECT_EQ(j["rows"][1]["paper"]["model"], "Bunny5");
  EXPECT_DOUBLE_EQ(j["rows"][1]["paper"]["xeon_3ghz_ms"].get<double>(), 0.99);
}

TEST(RunBench, ABackendAskedForByNameRunsOrIsAnErrorNeverACpuRow) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_bench_gl";
  const auto r = test::run_organsim("bench --sizes 300 --backend gl --repetitions 1 --steps 2 --warmup 0 --no-exude --json", dir);
  if (r.exit_code == 0) {
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["rows"].size(), 1u);
    EXPECT_EQ(j["rows"][0]["backend"], "gl");
  } else {
    test::expect_no_gl_context_here(r);  // never a quiet CPU row, never a broken backend
  }
}

}  // namespace
}  // namespace organsim
