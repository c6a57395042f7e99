// The scenario's mesh.scale scales the model: a tet mesh read at scale 2
// has 8 times the volume and mass (same density), and a surface is scaled
// before it is meshed, so cell sizes are in metres of the scaled surface.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <regex>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace mesh_scale_test {
namespace {

namespace fs = std::filesystem;

struct PlanModel {
  int points = 0;
  double mass = 0;    // kg
  double volume = 0;  // m^3
};

// `organsim run --plan` on the scenario with `mesh` replaced.
PlanModel plan_with_mesh(const nlohmann::json& mesh, const std::string& name) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / ("mesh_scale_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  nlohmann::json s = {{"mesh", mesh}, {"material", {{"density", 1000}, {"young_modulus", 5000}}}};
  std::ofstream(dir / "scene.json") << s.dump();
  const test::CliResult r = test::run_organsim("run --plan '" + (dir / "scene.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::smatch m;
  const std::regex line(R"(model: +(\d+) points \(\d+ fixed\), \d+ springs, \d+ tets, mass ([0-9.e+-]+) kg, volume ([0-9.e+-]+) m\^3)");
  PlanModel p;
  if (!std::regex_search(r.out, m, line)) {
    ADD_FAILURE() << "no model line in:\n" << r.out;
    return p;
  }
  p.points = std::stoi(m[1]);
  p.mass = std::stod(m[2]);
  p.volume = std::stod(m[3]);
  return p;
}

TEST(MeshScale, ATetMeshAtScaleTwoHasEightTimesTheVolumeAndMass) {
  const std::string box = (fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "stress" / "box.mesh").string();
  const PlanModel one = plan_with_mesh({{"tet", box}}, "tet1");
  const PlanModel two = plan_with_mesh({{"tet", box}, {"scale", 2}}, "tet2");
  // box.mesh is a 4 cm cube: 6.4e-5 m^3, 0.064 kg at 1000 kg/m^3 (the plan
  // prints 6 significant digits, hence 1e-5).
  EXPECT_NEAR(one.volume, 6.4e-5, 1e-5 * 6.4e-5);
  EXPECT_NEAR(two.volume / one.volume, 8.0, 1e-4);
  EXPECT_NEAR(two.mass / one.mass, 8.0, 1e-4);
  EXPECT_EQ(one.points, two.points);
}

TEST(MeshScale, ASurfaceIsScaledBeforeItIsMeshed) {
  // examples/box.off is 0.10 x 0.08 x 0.06 m (4.8e-4 m^3). In millimetres,
  // scale 0.001 gives it back; the cell size is in metres of the scaled box.
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "mesh_scale_surface";
  fs::create_directories(dir);
  std::ifstream in(fs::path(ORGANSIM_SOURCE_DIR) / "examples" / "box.off");
  std::ofstream mm(dir / "box_mm.off");
  std::string header;
  int nv = 0, nf = 0, ne = 0;
  in >> header >> nv >> nf >> ne;
  mm << "OFF\n" << nv << " " << nf << " 0\n";
  for (int i = 0; i < nv; ++i) {
    double x, y, z;
    in >> x >> y >> z;
    mm << x * 1000 << " " << y * 1000 << " " << z * 1000 << "\n";
  }
  for (std::string l; std::getline(in, l);) mm << l << "\n";
  mm.close();
  const nlohmann::json options = {{"cell_size", 0.02}, {"exude", false}};
  const PlanModel scaled =
      plan_with_mesh({{"surface", (dir / "box_mm.off").string()}, {"scale", 0.001}, {"options", options}}, "mm");
  const PlanModel metres = plan_with_mesh(
      {{"surface", (fs::path(ORGANSIM_SOURCE_DIR) / "examples" / "box.off").string()}, {"options", options}}, "m");
  // The same box in the same units: the same mesh (Mesh_3 is deterministic;
  // the millimetre coordinates times 0.001 are the metre ones up to rounding).
  EXPECT_NEAR(scaled.volume, metres.volume, 1e-3 * metres.volume);
  EXPECT_NEAR(scaled.points, metres.points, 0.02 * metres.points);
  // Mesh_3 does not protect the box's edges, so its volume is a little short of 4.8e-4.
  EXPECT_NEAR(metres.volume, 4.8e-4, 0.05 * 4.8e-4);
}

}  // namespace
}  // namespace mesh_scale_test
}  // namespace organsim
