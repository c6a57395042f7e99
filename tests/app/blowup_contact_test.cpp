// A blow-up while the tool presses on the tissue, on both backends: the run
// stops with the numerical exit code and leaves a force log that is valid
// JSON, says why it stopped, and holds only finite numbers, including the
// nonzero contact forces recorded before the stop. (Without a tool the force
// is identically zero, so a NaN check there proves nothing.)
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace blowup_contact_test {
namespace {

namespace fs = std::filesystem;

// scenarios/stress/dt_over.json (the 4 cm box, base fixed) with its mesh
// path made absolute, for a scene written into a fresh `dir`.
nlohmann::json stress_box_scene(const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path stress = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "stress";
  nlohmann::json s = nlohmann::json::parse(std::ifstream(stress / "dt_over.json"));
  s["mesh"]["tet"] = (stress / "box.mesh").string();
  return s;
}

void blow_up_in_contact(const std::string& backend) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / ("blowup_contact_" + backend);
  nlohmann::json s = stress_box_scene(dir);
  // dt 2.5 ms is 1.6 x dt_crit of the box alone (1.55 ms), more with the
  // tool's contact stiffness: it diverges within a few hundred ticks.
  s["time"] = {{"duration", 1.0}, {"dt", 0.0025}, {"substeps", 1}};
  s["backend"] = {{"name", backend}};
  // The 1 cm sphere starts 3 mm into the 4 cm box's top face and keeps pressing.
  s["tool"] = {{"radius", 0.01},
               {"contact_stiffness", 500},
               {"mode", "push"},
               {"keyframes", {{{"t", 0.0}, {"position", {0.02, 0.02, 0.047}}},
                              {{"t", 1.0}, {"position", {0.02, 0.02, 0.040}}}}}};
  std::ofstream(dir / "scene.json") << s.dump(2);
  const test::CliResult r =
      test::run_organsim("run '" + (dir / "scene.json").string() + "' --allow-unstable -o '" + (dir / "out").string() + "'", dir);
  if (backend == "gl" && r.exit_code == 6) {
    test::expect_no_gl_context_here(r);
    return;
  }
  ASSERT_EQ(r.exit_code, 5) << r.out << r.err;  // ErrorKind::Numerical: stopped by a blow-up check
  const nlohmann::json log = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  EXPECT_EQ(log["meta"]["backend"], backend);
  EXPECT_FALSE(log["meta"]["completed"].get<bool>());
  // The log says why, in the words of the error the user saw, with the time.
  const std::string reason = log["meta"]["stop_reason"].get<std::string>();
  EXPECT_NE(reason.find("t = "), std::string::npos) << reason;
  EXPECT_NE(r.err.find("organsim: error: " + reason), std::string::npos) << r.err;
  const auto& force = log["samples"]["force"];
  ASSERT_GT(force.size(), 0u);
  EXPECT_LT(force.size(), 1000u) << "the run was not stopped";
  double largest = 0;
  for (const auto& f : force) {
    ASSERT_EQ(f.size(), 3u);
    for (const auto& c : f) {
      ASSERT_TRUE(c.is_number()) << "null (NaN) in the force log: " << f.dump();
      ASSERT_TRUE(std::isfinite(c.get<double>()));
      largest = std::max(largest, std::abs(c.get<double>()));
    }
  }
  // 3 mm into the box at 500 N/m: about a newton; anything above 1 mN means
  // the tool really was in contact.
  EXPECT_GT(largest, 1e-3);
  for (const auto& t : log["samples"]["torque"])
    for (const auto& c : t) ASSERT_TRUE(c.is_number()) << t.dump();
}

TEST(BlowupInContact, CpuStopsWithAFiniteForceLog) { blow_up_in_contact("cpu"); }
TEST(BlowupInContact, GlStopsWithAFiniteForceLog) { blow_up_in_contact("gl"); }

// The opposite case: a stable run whose pulling tool grasps at t = 0 and
// moves from the first tick on, checked every tick. The tool's work in the
// first tick is part of the energy budget, so the check stays quiet (a budget
// that skipped it stopped this run at the first check).
TEST(BlowupInContact, GraspPullingFromTheFirstTickIsNotABlowUp) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "blowup_grasp_first_tick";
  nlohmann::json s = stress_box_scene(dir);
  s["time"] = {{"duration", 0.02}, {"dt", 0.0002}, {"substeps", 5}};
  s["tool"] = {{"radius", 0.005},
               {"contact_stiffness", 2000},
               {"mode", "pull"},
               {"grasp_radius", 0.012},
               {"grasp_time", 0.0},
               {"keyframes", {{{"t", 0.0}, {"position", {0.02, 0.02, 0.04}}},
                              {{"t", 0.1}, {"position", {0.022, 0.02, 0.038}}}}}};
  std::ofstream(dir / "scene.json") << s.dump(2);
  const test::CliResult r = test::run_organsim(
      "run '" + (dir / "scene.json").string() + "' --backend cpu --check-interval 1 -o '" + (dir / "out").string() + "'",
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("grasp:"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("grasp:    0 points"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace blowup_contact_test
}  // namespace organsim
