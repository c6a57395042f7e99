// scenarios/liver_push.json on the CPU backend, through the CLI (meshing
// included): no force before contact, a force opposing the push once in
// contact, growing with depth. The scenario file itself is what is tested.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "tests/app/run_cli_test_util.h"

namespace organsim {
namespace run_liver_push_test {
namespace {

namespace fs = std::filesystem;

TEST(RunLiverPush, NoForceBeforeContactThenOpposingAndGrowingWithDepth) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "run_liver_push";
  fs::remove_all(dir);
  const fs::path scene = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "liver_push.json";
  const auto r = test::run_organsim("run '" + scene.string() + "' -o '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::slurp(dir / "out" / "forces.json"));
  const auto& s = j["samples"];
  const size_t n = s["t"].size();
  ASSERT_EQ(n, 1000u);  // 1 s at 1 kHz
  ASSERT_EQ(j["meta"]["completed"], true);

  // The tool moves straight down (-z): the push direction.
  const double z0 = s["tool_position"][0][2], z1 = s["tool_position"][n - 1][2];
  ASSERT_LT(z1, z0);

  // Contact begins at the first tick with a contact point. The tool's bottom
  // (centre z - 2 cm) starts 1 cm above the undeformed top (z = 0.058 m on the
  // tool's path) and descends at 3.5 cm/s: contact at t = 0.29 s if the liver
  // did not move; it has sagged under gravity away from the tool before t = 0
  // (time.settle), so contact must start after 0.25 s and well before the end.
  size_t first = n;
  for (size_t i = 0; i < n; ++i) {
    if (s["contacts"][i].get<int>() > 0) {
      first = i;
      break;
    }
  }
  ASSERT_LT(first, n) << "the tool never touched the liver";
  const double t_contact = s["t"][first];
  EXPECT_GT(t_contact, 0.25);
  EXPECT_LT(t_contact, 0.7);
  // Before contact: exactly zero force (penalty contact acts only on points inside the tool).
  for (size_t i = 0; i < first; ++i) {
    for (int c = 0; c < 3; ++c) ASSERT_EQ(s["force"][i][c].get<double>(), 0.0) << "t = " << s["t"][i];
  }
  // Once the tool is 50 ms into contact, the reaction points up, against the push.
  for (size_t i = first + 50; i < n; ++i) {
    ASSERT_GT(s["force"][i][2].get<double>(), 0.0) << "t = " << s["t"][i];
  }
  // Growing with depth: mean upward force over three 50 ms windows at
  // increasing depth, each at least 20 % above the previous one (the contact
  // is a few points, so single samples are noisy; windows are not).
  auto mean_fz = [&](double from, double to) {
    double sum = 0;
    int count = 0;
    for (size_t i = 0; i < n; ++i) {
      const double t = s["t"][i];
      if (t >= from && t < to) {
        sum += s["force"][i][2].get<double>();
        ++count;
      }
    }
    return sum / count;
  };
  const double f1 = mean_fz(t_contact + 0.15, t_contact + 0.2);
  const double f2 = mean_fz(t_contact + 0.3, t_contact + 0.35);
  const double f3 = mean_fz(0.95, 1.0);
  EXPECT_GT(f1, 0.0);
  EXPECT_GT(f2, 1.2 * f1);
  EXPECT_GT(f3, 1.2 * f2);
  // Soft tissue (E = 8 kPa) under a 2 cm sphere 1-2 cm deep: newtons, not
  // millinewtons or kilonewtons (sanity of units, a factor 10 either way).
  EXPECT_GT(f3, 0.3);
  EXPECT_LT(f3, 30.0);
}

}  // namespace
}  // namespace run_liver_push_test
}  // namespace organsim
