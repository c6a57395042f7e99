// scenarios/liver_suture.json through the CLI (meshing, frames and contact
// sheet included): the liver_cut blade opens the lobe, sutures tied along the
// cut at 0.2 s close it without pulling harder than the tissue needs,
// meta.events and meta.sutures say so, --plan lists them.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace run_liver_suture_test {
namespace {

namespace fs = std::filesystem;

TEST(RunLiverSuture, SuturesAlongTheCutCloseIt) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_liver_suture";
  fs::remove_all(dir);
  const fs::path scene = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "liver_suture.json";
  const auto r = test::run_organsim("run '" + scene.string() + "' -o '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  const auto& meta = j["meta"];
  ASSERT_EQ(meta["completed"], true);
  const auto& events = meta["events"];
  ASSERT_GT(events.size(), 3u);
  const auto& tie = events.back();
  EXPECT_EQ(tie["kind"], "suture");
  EXPECT_DOUBLE_EQ(tie["t"].get<double>(), 0.2);
  EXPECT_EQ(tie["sources"][0]["along"], "incision");
  EXPECT_EQ(tie["points_added"], 0);  // a suture adds springs, not points
  EXPECT_GT(tie["sutures_added"].get<int>(), 10);  // a row along a 14 cm cut, one every 8 mm
  EXPECT_LT(meta["dt"].get<double>(), tie["dt_crit_guaranteed"].get<double>());
  for (size_t i = 0; i + 1 < events.size(); ++i) EXPECT_EQ(events[i]["kind"], "cut");
  // The cut had opened (the longest suture was tied across more than 5 mm)
  // and at 0.8 s no suture's ends are more than 10 % of that apart: the
  // rest lengths reached zero at 0.2 s + 22 mm / (5 cm/s) = 0.65 s.
  const auto& sutures = meta["sutures"];
  EXPECT_EQ(sutures["count"], tie["sutures"]);
  const double opening = sutures["tied_length_max_m"];
  EXPECT_GT(opening, 5e-3);
  EXPECT_LT(sutures["length_max_m"].get<double>(), 0.1 * opening);
  // Bounded at every tick, not only at the end: tightening at 5 cm/s, the
  // tissue follows, and the largest tension any suture reached at the end of
  // a tick was 0.16 N (0.045 N at the end, on the lobe's weight; the run is
  // deterministic; poisson_ratio 0.45, whose lobe sags further than the
  // per-tet volume_modulus material's, which opened 17 mm and peaked at
  // 0.20 N). 0.4 N is 2.4 times that and a fiftieth of what a suture pulls
  // when the tissue does not follow (its stiffness times the opening, 22 N):
  // sutures tightening 10 times faster than the tissue follows reach 0.47 N.
  EXPECT_LE(sutures["tension_end_N"].get<double>(), sutures["tension_max_N"].get<double>());
  EXPECT_LT(sutures["tension_max_N"].get<double>(), 0.4);
  const auto sheet = test::slurp(dir / "out" / "contact_sheet.png");
  ASSERT_GT(sheet.size(), 8u);
  EXPECT_EQ(sheet.substr(1, 3), "PNG");

  const auto plan = test::run_organsim("run '" + scene.string() + "' --plan", dir);
  ASSERT_EQ(plan.exit_code, 0) << plan.err;
  EXPECT_NE(plan.out.find("sutures at t = 0.2 s: along cut \"incision\", 1000 N/m each"), std::string::npos)
      << plan.out;
}

}  // namespace
}  // namespace run_liver_suture_test
}  // namespace organsim
