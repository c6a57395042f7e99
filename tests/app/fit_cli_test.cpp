// `organsim fit` end to end on a tiny model: a synthetic measured curve made
// by `organsim run` with known (E, nu) is fitted from a start 3x away.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace fit_cli_test {
namespace {

namespace fs = std::filesystem;

// The stress-test box (4 cm, 125 points), base held, its top grasped and
// moved 2 mm sideways and 2 mm down in 0.1 s: the sideways force follows the
// shear modulus, the downward one the confined compression, so E and nu are
// both in the curve.
void write_scenario(const fs::path& path, double young, double nu) {
  nlohmann::json s = {
      {"mesh", {{"tet", std::string(ORGANSIM_SOURCE_DIR) + "/scenarios/stress/box.mesh"}}},
      {"material",
       {{"density", 1000}, {"young_modulus", young}, {"poisson_ratio", nu}, {"spring_damping_time", 0.001},
        {"viscous_damping", 20}}},
      {"fixed", {{{"plane", {{"point", {0, 0, 0.0001}}, {"normal", {0, 0, -1}}}}}}},
      {"gravity", {0, 0, 0}},
      {"time", {{"duration", 0.1}, {"dt", 0.0002}, {"substeps", 5}}},
      {"tool",
       {{"shape", "sphere"}, {"radius", 0.005}, {"contact_stiffness", 2000}, {"mode", "pull"},
        {"grasp_radius", 0.012}, {"grasp_time", 0},
        {"keyframes", {{{"t", 0.0}, {"position", {0.02, 0.02, 0.04}}}, {{"t", 0.1}, {"position", {0.022, 0.02, 0.038}}}}}}},
      {"backend", {{"threads", 1}}},  // no thread timing in each of the fit's many runs
      {"outputs", {{"forces", true}}}};
  std::ofstream(path) << s.dump(2);
}

TEST(FitCli, RecoversYoungModulusAndPoissonRatioFromAStartThreeTimesOff) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "fit_cli";
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_scenario(dir / "truth.json", 6000, 0.4);
  const auto truth = test::run_organsim("run " + (dir / "truth.json").string() + " -o " + (dir / "truth").string(), dir / "t");
  ASSERT_EQ(truth.exit_code, 0) << truth.err;
  const nlohmann::json log = nlohmann::json::parse(test::slurp(dir / "truth" / "forces.json"));
  {
    std::ofstream csv(dir / "curve.csv");
    csv << "# synthetic: E 6000 Pa, nu 0.4\nt,fx,fz\n";
    const auto& t = log["samples"]["t"];
    const auto& f = log["samples"]["force"];
    for (size_t i = 0; i < t.size(); ++i) csv << t[i].get<double>() << "," << f[i][0].get<double>() << "," << f[i][2].get<double>() << "\n";
  }
  write_scenario(dir / "start.json", 18000, 0.3);  // E 3x off, nu 0.1 off
  const auto fit = test::run_organsim("fit " + (dir / "start.json").string() + " --measured " +
                                          (dir / "curve.csv").string() +
                                          " --param material.young_modulus,material.poisson_ratio -o " +
                                          (dir / "fit").string(),
                                      dir / "f");
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const nlohmann::json j = nlohmann::json::parse(test::slurp(dir / "fit" / "fit.json"));
  ASSERT_EQ(j["parameters"].size(), 2u);
  // The target: within 2 % of the values that made the curve.
  EXPECT_NEAR(j["parameters"][0]["fitted"].get<double>(), 6000, 0.02 * 6000) << j.dump(1);
  EXPECT_NEAR(j["parameters"][1]["fitted"].get<double>(), 0.4, 0.02 * 0.4) << j.dump(1);
  EXPECT_EQ(j["parameters"][0]["start"].get<double>(), 18000);
  EXPECT_LE(j["iterations"].get<int>(), 20);
  EXPECT_EQ(j["curve"]["fx"]["measured"].size(), j["curve"]["x"].size());
  // The fitted run's force log carries the fit in its meta.
  const nlohmann::json flog = nlohmann::json::parse(test::slurp(dir / "fit" / "forces.json"));
  EXPECT_NEAR(flog["meta"]["fit"]["parameters"][0]["fitted"].get<double>(), j["parameters"][0]["fitted"].get<double>(), 1e-9);
  // Every run's meta states the elasticity its material stands for.
  EXPECT_EQ(flog["meta"]["elasticity"]["rule"], "poisson_ratio");
  EXPECT_NEAR(flog["meta"]["elasticity"]["poisson_ratio"].get<double>(), j["parameters"][1]["fitted"].get<double>(), 1e-9);
  // fit.png: a real PNG.
  const std::string png = test::slurp(dir / "fit" / "fit.png");
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
}

TEST(FitCli, BadMeasuredCurveNamesFileAndLine) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "fit_cli_bad";
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_scenario(dir / "s.json", 6000, 0.4);
  std::ofstream(dir / "bad.csv") << "t,fz\n0.001,0.5\n0.002,oops\n";
  const auto r = test::run_organsim("fit " + (dir / "s.json").string() + " --measured " + (dir / "bad.csv").string() +
                                        " --param material.young_modulus -o " + (dir / "out").string(),
                                    dir / "r");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("bad.csv: line 3: column 2: expected a number"), std::string::npos) << r.err;
  const auto p = test::run_organsim("fit " + (dir / "s.json").string() + " --measured " + (dir / "bad.csv").string() +
                                        " --param material.stiffness", dir / "p");
  EXPECT_EQ(p.exit_code, 2);
  EXPECT_NE(p.err.find("unknown parameter 'material.stiffness'"), std::string::npos) << p.err;
}

}  // namespace
}  // namespace fit_cli_test
}  // namespace organsim
