// `organsim validate` end to end at one coarse cell size: the three files
// are there, parse, and hold every case with measured, theory and error, and
// the measured E and nu are near what was asked.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace {

namespace fs = std::filesystem;

TEST(ValidateCli, WritesTablesAndPlotForEveryCase) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli";
  fs::remove_all(dir);
  const auto r = test::run_organsim("validate --cell-size 0.02 --poisson-ratio springs,0.4 -o " + (dir / "out").string(),
                                    dir / "log");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(test::slurp(dir / "out" / "validation.json"));
  std::set<std::string> tests;
  for (const auto& row : j["rows"]) {
    tests.insert(row["test"].get<std::string>());
    const double measured = row["measured"], theory = row["theory"], error = row["error"];
    const double expected = row["error_kind"] == "ratio" ? measured / theory : measured - theory;
    EXPECT_NEAR(error, expected, 1e-12);
    EXPECT_GT(row["points"].get<int>(), 0);
  }
  for (const char* t : {"uniaxial E", "uniaxial nu", "cantilever tip load", "cantilever guided", "hertz d/R=0.1",
                        "hertz probe d/R=0.2"})
    EXPECT_TRUE(tests.count(t)) << t;
  EXPECT_EQ(j["rows"].size(), 2u * 8u);  // 2 materials x 8 quantities
  // The measured E and nu against what was asked (E 10 kPa, the default;
  // nu 1/4 for the springs alone, 0.4): at these 20 mm cells E is 0.80 and
  // 0.83 of the asked value (it converges from below as the cells shrink,
  // docs/validation.md), nu within 0.003. The bounds (E within 0.7-1.05 of
  // the asked value, nu within 0.03, the validation target) fail for a spring
  // stiffness off by a factor 1.5 or a lost volume term (nu near 1/4).
  int checked = 0;
  for (const auto& row : j["rows"]) {
    const double asked_nu = row["material"] == "nu 0.40" ? 0.4 : 0.25;
    if (row["test"] == "uniaxial E") {
      EXPECT_EQ(row["theory"].get<double>(), 10e3);
      EXPECT_GT(row["measured"].get<double>(), 0.7 * 10e3) << row["material"];
      EXPECT_LT(row["measured"].get<double>(), 1.05 * 10e3) << row["material"];
      ++checked;
    } else if (row["test"] == "uniaxial nu") {
      EXPECT_EQ(row["theory"].get<double>(), asked_nu);
      EXPECT_NEAR(row["measured"].get<double>(), asked_nu, 0.03) << row["material"];
      ++checked;
    }
  }
  EXPECT_EQ(checked, 4);  // E and nu for both materials
  const std::string csv = test::slurp(dir / "out" / "validation.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 16);
  const std::string png = test::slurp(dir / "out" / "validation.png");
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
}

TEST(ValidateCli, BadPoissonRatioIsAUsageError) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_bad";
  const auto r = test::run_organsim("validate --poisson-ratio 0.5 -o " + (dir / "out").string(), dir / "log");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--poisson-ratio"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace organsim
