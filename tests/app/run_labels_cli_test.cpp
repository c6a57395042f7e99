// `organsim run` on a mesh with per-label materials: --plan lists each
// label's material and names the label whose cells limit dt_crit, and the
// force log's meta gives the elasticity per label.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "core/mesh/mesh_io.h"
#include "core/mesh/tet_mesh.h"
#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace run_labels_cli_test {
namespace {

namespace fs = std::filesystem;
using test::run_organsim;
using json = nlohmann::json;

// A 4 cm cube of 4 x 4 x 4 cells, label 1 for x < 2 cm and label 2 beyond,
// with the two labels' Young's moduli; the scenario next to it.
fs::path write_two_label_scene(const std::string& name, double e1, double e2) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_labels_cli" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.04, 0.04, 0.04), 4, 4, 4);
  for (const Tet& t : mesh.tets) {
    const double x = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]] + mesh.points[t[3]]).x() / 4;
    mesh.labels.push_back(x < 0.02 ? 1 : 2);
  }
  write_tet_mesh(dir / "cube.mesh", mesh);
  const json material = {{"poisson_ratio", 0.45}, {"density", 1000}, {"viscous_damping", 1}};
  json m1 = material, m2 = material;
  m1["labels"] = {1};
  m1["young_modulus"] = e1;
  m2["labels"] = {2};
  m2["young_modulus"] = e2;
  const json scenario = {{"mesh", {{"tet", "cube.mesh"}}},
                         {"materials", {m1, m2}},
                         {"fixed", {{{"plane", {{"point", {0, 0, 0.001}}, {"normal", {0, 0, -1}}}}}}},
                         {"time", {{"duration", 0.02}, {"dt", 0.00002}, {"substeps", 50}}},
                         {"backend", {{"threads", 1}}}};
  std::ofstream(dir / "scene.json") << scenario.dump(2);
  return dir;
}

TEST(RunLabelsCli, PlanListsEachLabelsMaterialAndTheLabelThatLimitsTheStep) {
  // The stiff label's cells hold the top mode (same cells, same density, 100x E).
  for (const auto& [stiff, e1, e2] : {std::tuple{2, 3000.0, 300000.0}, std::tuple{1, 300000.0, 3000.0}}) {
    const fs::path dir = write_two_label_scene("plan_stiff_" + std::to_string(stiff), e1, e2);
    const auto r = run_organsim("run '" + (dir / "scene.json").string() + "' --plan", dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("materials per label:\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("  - label 1: density 1000 kg/m^3, rule poisson_ratio, E " + (e1 == 3000 ? std::string("3000") : "300000") +
                         " Pa, nu 0.45"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("  - label 2: density 1000 kg/m^3, rule poisson_ratio, E " + (e2 == 3000 ? std::string("3000") : "300000") +
                         " Pa, nu 0.45"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("limited by label " + std::to_string(stiff) + "'s cells"), std::string::npos) << r.out;
  }
}

TEST(RunLabelsCli, ForceLogGivesTheElasticityAndTheTopModePerLabel) {
  const fs::path dir = write_two_label_scene("meta", 3000, 300000);
  const auto r = run_organsim("run '" + (dir / "scene.json").string() + "' -o '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json log;
  std::ifstream(dir / "out" / "forces.json") >> log;
  const json& per_label = log["meta"]["elasticity"]["per_label"];
  ASSERT_EQ(per_label.size(), 2u) << log["meta"]["elasticity"].dump();
  EXPECT_EQ(per_label[0]["labels"], json({1}));
  EXPECT_EQ(per_label[1]["labels"], json({2}));
  // With a Poisson ratio the effective E and nu are the asked ones (rounding only).
  EXPECT_NEAR(per_label[0]["young_modulus"].get<double>(), 3000, 1e-6);
  EXPECT_NEAR(per_label[1]["young_modulus"].get<double>(), 300000, 1e-4);
  EXPECT_NEAR(per_label[1]["poisson_ratio"].get<double>(), 0.45, 1e-12);
  EXPECT_EQ(per_label[1]["rule"], "poisson_ratio");
  EXPECT_EQ(per_label[1]["density"], 1000);
  // The top mode's shares per label sum to 1, the stiff label first.
  const json& shares = log["meta"]["stability"]["label_shares"];
  ASSERT_EQ(shares.size(), 2u) << log["meta"]["stability"].dump();
  EXPECT_EQ(shares[0]["label"], 2);
  EXPECT_GT(shares[0]["share"].get<double>(), 0.9);
  EXPECT_NEAR(shares[0]["share"].get<double>() + shares[1]["share"].get<double>(), 1.0, 1e-9);
}

}  // namespace
}  // namespace run_labels_cli_test
}  // namespace organsim
