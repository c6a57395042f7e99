// scenarios/liver_cut.json through the CLI (meshing, frames and contact
// sheet included): the blade opens the lobe, every change is in meta.events
// with counts that add up, mass and output numbering stay as documented.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace {

namespace fs = std::filesystem;

TEST(RunLiverCut, TheBladeSplitsPointsAndEveryChangeIsLogged) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_liver_cut";
  fs::remove_all(dir);
  const fs::path scene = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "liver_cut.json";
  const auto r = test::run_organsim("run '" + scene.string() + "' -o '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  const auto& meta = j["meta"];
  ASSERT_EQ(meta["completed"], true);
  EXPECT_EQ(j["samples"]["t"].size(), 1000u);  // samples continue across the changes
  const auto& events = meta["events"];
  ASSERT_GT(events.size(), 3u);  // a progressive cut: several changes
  int points = meta["points"], added = 0, faces = 0;
  double last_t = -1;
  for (const auto& e : events) {
    EXPECT_EQ(e["kind"], "cut");
    EXPECT_EQ(e["sources"][0]["name"], "incision");
    // The blade moves from 0 to 20 ms: changes happen at tick starts within it.
    EXPECT_GE(e["t"].get<double>(), 0.0);
    EXPECT_LT(e["t"].get<double>(), 0.02);
    EXPECT_GT(e["t"].get<double>(), last_t);
    last_t = e["t"];
    added += e["points_added"].get<int>();
    faces += e["faces_separated"].get<int>();
    EXPECT_EQ(e["points"].get<int>(), points + e["points_added"].get<int>());
    points = e["points"];
    // The run's dt stays below the new version's guaranteed step, so the
    // full estimate was not needed (docs/topology.md).
    EXPECT_EQ(e["dt_check"], "gershgorin");
    EXPECT_FALSE(e.contains("dt_crit"));
    EXPECT_LT(meta["dt"].get<double>(), e["dt_crit_guaranteed"].get<double>());
  }
  EXPECT_EQ(meta["final_points"].get<int>(), meta["points"].get<int>() + added);
  // A blade across the lobe's root: tens of faces, not a handful.
  EXPECT_GT(faces, 40);
  EXPECT_GT(added, 20);
  // The contact sheet was written (its pixels are checked by the render tests).
  const auto sheet = test::slurp(dir / "out" / "contact_sheet.png");
  ASSERT_GT(sheet.size(), 8u);
  EXPECT_EQ(sheet.substr(1, 3), "PNG");
}

TEST(RunLiverCut, PlanSaysWhetherThereIsATopologyPass) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "plan_topology";
  const fs::path root = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios";
  const auto cut = test::run_organsim("run '" + (root / "liver_cut.json").string() + "' --plan", dir);
  ASSERT_EQ(cut.exit_code, 0) << cut.err;
  EXPECT_NE(cut.out.find("topology: 1 cut"), std::string::npos) << cut.out;
  EXPECT_EQ(cut.out.find("no topology pass"), std::string::npos);
  const auto push = test::run_organsim("run '" + (root / "liver_push.json").string() + "' --plan", dir);
  ASSERT_EQ(push.exit_code, 0) << push.err;
  EXPECT_NE(push.out.find("no topology pass"), std::string::npos) << push.out;
}

}  // namespace
}  // namespace organsim
