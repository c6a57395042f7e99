// `organsim validate` end to end at one coarse cell size: the three files
// are there, parse, and hold every case with measured, theory and error, and
// the measured E and nu are near what was asked.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace validate_cli_test {
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
                        "hertz as run d/R=0.1", "hertz probe d/R=0.2"})
    EXPECT_TRUE(tests.count(t)) << t;
  EXPECT_EQ(j["rows"].size(), 2u * 11u);  // 2 materials x 11 quantities
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
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 22);
  const std::string png = test::slurp(dir / "out" / "validation.png");
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
}

// The line load's independent expectation: a 2-D estimate of a rigid
// cylinder (radius R, pressed d) on an elastic layer of thickness h on a
// rigid base, per unit length P. The contact is 2-D Hertz, half-width
// a = sqrt(4 P R / (pi E')), pressure p0 sqrt(1 - x^2/a^2), p0 a = 2 P / pi;
// its stresses on the axis are the half-space's (McEwen):
//   sigma_z = -p0 a / sqrt(a^2 + z^2),
//   sigma_x = -(p0 / a) ((a^2 + 2 z^2) / sqrt(a^2 + z^2) - 2 z),
// and d is the shortening of the column under the axis down to the base,
// the integral of -eps_z over 0..h:
//   d = (2 P / (pi E)) (c1 asinh(h / a) - c2 (h sqrt(a^2 + h^2) - h^2) / a^2),
// in plane strain (a body long along the axis: E' = E / (1 - nu^2),
// c1 = 1 - nu^2, c2 = nu (1 + nu)) or plane stress (a thin one: E' = E,
// c1 = 1, c2 = nu). Assumed: small strain, frictionless, the base's effect
// on the stresses neglected (they are the half-space's down to h), the
// body wide across the axis. The validation block (0.08 x 0.04 x 0.03 m,
// the capsule across its 4 cm) is neither long nor thin: u_y = 0 everywhere
// (plane strain) is a constraint it lacks, so plane strain is the stiffer
// estimate, and its free ends make it stiffer than plane stress. Solved for
// P by bisection (d grows with P); the force is P times the block's 4 cm.
double line_load_estimate(double depth, double E, double nu, bool plane_strain) {
  const double R = 0.005, h = 0.03, length = 0.04, kPi = 3.141592653589793;
  const double e_prime = plane_strain ? E / (1 - nu * nu) : E;
  const double c1 = plane_strain ? 1 - nu * nu : 1, c2 = plane_strain ? nu * (1 + nu) : nu;
  auto depth_at = [&](double P) {
    const double a = std::sqrt(4 * P * R / (kPi * e_prime));
    return 2 * P / (kPi * E) * (c1 * std::asinh(h / a) - c2 * (h * std::sqrt(a * a + h * h) - h * h) / (a * a));
  };
  double lo = 1e-6, hi = 1e4;  // N/m
  for (int i = 0; i < 200; ++i) {
    const double mid = std::sqrt(lo * hi);
    (depth_at(mid) < depth ? lo : hi) = mid;
  }
  return lo * length;
}

// The line-load case (nu 0.4, E 10 kPa) on 20 and 12 mm cells against an
// 8 mm reference mesh, which neither shares. The 12 mm rows and the
// reference lie within [0.9 x plane stress, plane strain] of the estimate
// above: measured 0.96-1.12 of plane stress and 0.76-0.88 of plane strain
// (the 2.5 mm mesh of docs/validation.md at nu 0.45: 0.97-1.08 and
// 0.70-0.81); the 0.9 leaves room for the finer meshes' further fall (4-6 %
// from 3.5 to 2.5 mm). Without the line layer the reference is 1.18-1.34
// times plane strain at 1 and 2 mm, outside. The 12 mm rows are within the
// 15 % target of the reference (measured 0.90-1.04); the 20 mm cells (141
// points), three times the 7 mm contact strip, miss it at 4 mm (1.29). Each
// row's verdict is checked against the 15 % written here.
TEST(ValidateCli, LineLoadAgreesWithAFinerMeshAndLiesBetweenThePlaneStressAndPlaneStrainEstimates) {
  constexpr double kTarget = 0.15, kReference = 0.008;
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_line_load";
  fs::remove_all(dir);
  const auto r = test::run_organsim("validate --cell-size 0.02,0.012 --poisson-ratio 0.4 --line-load-reference 0.008 "
                                    "--cases line-load -o " + (dir / "out").string(),
                                    dir / "log");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(test::slurp(dir / "out" / "validation.json"));
  EXPECT_EQ(j["line_load"]["reference_cell_size"].get<double>(), kReference);
  EXPECT_EQ(j["cases"], nlohmann::json::array({"line-load"}));
  const double depths[] = {0.001, 0.002, 0.004};
  ASSERT_EQ(j["rows"].size(), 2u * 3u);  // 2 cell sizes x depths 1, 2, 4 mm
  int passed = 0;
  for (size_t k = 0; k < j["rows"].size(); ++k) {
    const auto& row = j["rows"][k];
    const double depth = depths[k % 3], cell = row["cell_size"];
    char test[48];
    std::snprintf(test, sizeof test, "line load d=%gmm", depth * 1000);
    ASSERT_EQ(row["test"], test);
    EXPECT_EQ(cell, k < 3 ? 0.02 : 0.012);
    const double measured = row["measured"], reference = row["theory"], error = row["error"];
    EXPECT_NEAR(error, measured / reference, 1e-12);
    EXPECT_EQ(row["tolerance"].get<double>(), kTarget);
    EXPECT_EQ(row["pass"].get<bool>(), std::abs(measured / reference - 1) <= kTarget) << test << " at " << cell;
    passed += row["pass"].get<bool>();
    const double strain = line_load_estimate(depth, 10e3, 0.4, true), stress = line_load_estimate(depth, 10e3, 0.4, false);
    EXPECT_GT(strain, stress);
    EXPECT_GT(reference, 0.9 * stress) << test << ": the 8 mm reference against plane stress " << stress << " N";
    EXPECT_LT(reference, strain) << test << ": the 8 mm reference against plane strain " << strain << " N";
    if (cell == 0.012) {
      EXPECT_GT(measured, 0.9 * stress) << test << " at 12 mm against plane stress " << stress << " N";
      EXPECT_LT(measured, strain) << test << " at 12 mm against plane strain " << strain << " N";
      EXPECT_TRUE(row["pass"].get<bool>()) << test << " at 12 mm: " << error;
    }
  }
  EXPECT_FALSE(j["rows"][2]["pass"].get<bool>()) << "20 mm, d = 4 mm: " << j["rows"][2]["error"];
  EXPECT_LT(passed, 6);
  const std::string csv = test::slurp(dir / "out" / "validation.csv");
  EXPECT_NE(csv.find("tolerance,pass\n"), std::string::npos);
  EXPECT_NE(csv.find("line load d=2mm,nu 0.40,0.012,"), std::string::npos);
  EXPECT_NE(csv.find(",ratio,0.15,pass\n"), std::string::npos);
  EXPECT_NE(csv.find(",ratio,0.15,fail\n"), std::string::npos);
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
  EXPECT_NE(unknown.err.find("--cases: expected some of uniaxial, cantilever, hertz, hertz-run, probe, line-load, got "
                                   "'bending'"),
            std::string::npos)
      << unknown.err;
  const auto alone = test::run_organsim("validate --cases line-load -o " + (dir / "out").string(), dir / "log");
  EXPECT_EQ(alone.exit_code, 2);
  EXPECT_NE(alone.err.find("--line-load-reference"), std::string::npos) << alone.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "validation.json"));
}

TEST(ValidateCli, NonPositiveContactStiffnessIsAUsageError) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_bad_stiffness";
  const auto r = test::run_organsim("validate --cases hertz-run --contact-stiffness 0 -o " + (dir / "out").string(),
                                    dir / "log");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--contact-stiffness: expected a stiffness in N/m (> 0), got 0"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "validation.json"));
}

TEST(ValidateCli, BadPoissonRatioIsAUsageError) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_bad";
  const auto r = test::run_organsim("validate --poisson-ratio 0.5 -o " + (dir / "out").string(), dir / "log");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--poisson-ratio"), std::string::npos) << r.err;
}

// --shear-formulation per_tet runs the materials below nu = 1/4 on each
// tet's own deformation gradient instead of the smoothed element: the
// cantilever is markedly stiffer (docs/validation.md: 1.34 against 1.06 of
// theory at 12 mm for nu 0.1; at these 20 mm cells more), which a flag
// that changed nothing, or changed it the other way, would not give.
TEST(ValidateCli, ShearFormulationPerTetStiffensTheCantileverOverTheSmoothedElement) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "validate_cli_shear_formulation";
  fs::remove_all(dir);
  const auto tip_stiffness = [&](const std::string& flag, const std::string& name) {
    const auto r = test::run_organsim("validate --cases cantilever --cell-size 0.02 --poisson-ratio 0.1 " + flag +
                                          " -o " + (dir / name).string(),
                                      dir / (name + ".log"));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(test::slurp(dir / name / "validation.json"));
    for (const auto& row : j["rows"])
      if (row["test"] == "cantilever tip load") return row["measured"].get<double>();
    ADD_FAILURE() << "no cantilever tip load row in " << j.dump();
    return 0.0;
  };
  const double smoothed = tip_stiffness("", "default"), explicit_smoothed = tip_stiffness("--shear-formulation smoothed", "smoothed");
  const double per_tet = tip_stiffness("--shear-formulation per_tet", "per_tet");
  EXPECT_EQ(explicit_smoothed, smoothed);  // the default
  EXPECT_GT(per_tet, 1.1 * smoothed);
  const auto bad = test::run_organsim("validate --shear-formulation tet -o " + (dir / "bad").string(), dir / "bad.log");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--shear-formulation: expected 'smoothed' or 'per_tet', got 'tet'"), std::string::npos)
      << bad.err;
}

}  // namespace
}  // namespace validate_cli_test
}  // namespace organsim
