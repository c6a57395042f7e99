// `organsim validate` end to end at one coarse cell size: the three files
// are there, parse, and hold every case with measured, theory and error, and
// the measured E and nu are near what was asked.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

// The line-load case against its reference mesh: at the reference's own
// cell size the ratio is 1 (the same mesh, CGAL's meshing is deterministic),
// every row carries the 15 % target and its verdict in JSON and CSV. Run
// alone (--cases line-load): no other case's rows.
TEST(ValidateCli, LineLoadRowsCompareWithTheReferenceMeshAndCarryTheTarget) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_line_load";
  fs::remove_all(dir);
  const auto r = test::run_organsim("validate --cell-size 0.02,0.012 --poisson-ratio 0.4 --line-load-reference 0.012 "
                                    "--cases line-load -o " +
                                        (dir / "out").string(),
                                    dir / "log");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(test::slurp(dir / "out" / "validation.json"));
  EXPECT_EQ(j["line_load"]["reference_cell_size"].get<double>(), 0.012);
  EXPECT_EQ(j["cases"], nlohmann::json::array({"line-load"}));
  int rows = 0, at_reference = 0;
  for (const auto& row : j["rows"]) {
    ASSERT_EQ(row["test"].get<std::string>().rfind("line load d=", 0), 0u) << row["test"];
    ++rows;
    const double error = row["error"];
    EXPECT_GT(row["theory"].get<double>(), 0) << row["test"];
    EXPECT_EQ(row["tolerance"].get<double>(), 0.15);
    EXPECT_EQ(row["pass"].get<bool>(), std::abs(error - 1) <= 0.15) << row["test"] << " error " << error;
    if (row["cell_size"].get<double>() == 0.012) {
      EXPECT_NEAR(error, 1.0, 1e-12) << row["test"];
      ++at_reference;
    }
  }
  EXPECT_EQ(rows, 2 * 3);  // 2 cell sizes x depths 1, 2, 4 mm
  EXPECT_EQ(at_reference, 3);
  const std::string csv = test::slurp(dir / "out" / "validation.csv");
  EXPECT_NE(csv.find("tolerance,pass\n"), std::string::npos);
  EXPECT_NE(csv.find("line load d=2mm,nu 0.40,0.012,"), std::string::npos);
  EXPECT_NE(csv.find(",ratio,0.15,pass\n"), std::string::npos);  // at least the reference's own rows
}

TEST(ValidateCli, NegativeLineLoadReferenceIsAUsageError) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_bad_line_load";
  const auto r = test::run_organsim("validate --line-load-reference -0.002 -o " + (dir / "out").string(), dir / "log");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--line-load-reference"), std::string::npos) << r.err;
}

// An unknown case, and the line load without its reference, are usage errors naming the option.
TEST(ValidateCli, UnknownCaseOrALineLoadWithoutItsReferenceIsAUsageError) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_bad_cases";
  const auto unknown = test::run_organsim("validate --cases hertz,bending -o " + (dir / "out").string(), dir / "log");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("--cases: expected some of uniaxial, cantilever, hertz, probe, line-load, got 'bending'"),
            std::string::npos)
      << unknown.err;
  const auto alone = test::run_organsim("validate --cases line-load -o " + (dir / "out").string(), dir / "log");
  EXPECT_EQ(alone.exit_code, 2);
  EXPECT_NE(alone.err.find("--line-load-reference"), std::string::npos) << alone.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "validation.json"));
}

TEST(ValidateCli, BadPoissonRatioIsAUsageError) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_bad";
  const auto r = test::run_organsim("validate --poisson-ratio 0.5 -o " + (dir / "out").string(), dir / "log");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--poisson-ratio"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace organsim
