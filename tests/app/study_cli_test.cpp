// `organsim study` end to end on the small gentle-push box: the reference
// converges, a dt above dt_crit is reported unstable with its reason, stable
// runs have small errors that shrink with dt, and the three files are there.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace {

namespace fs = std::filesystem;

int run(const std::string& args, std::string& output) {
  const std::string cmd = std::string(ORGANSIM_EXE) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return -1;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) output.append(buf, n);
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(StudyCli, GentlePushStudy) {
  const fs::path out = fs::path(ORGANSIM_TEST_TMP) / "study_gentle";
  fs::remove_all(out);
  std::string output;
  const int code = run("study " + std::string(ORGANSIM_SOURCE_DIR) +
                           "/scenarios/stress/gentle_push.json --dt 0.002,0.0005,0.00025 --precision double,float "
                           "--duration 0.1 --threads 1 -o " + out.string(),
                       output);
  ASSERT_EQ(code, 0) << output;
  for (const char* f : {"study.json", "study.csv", "study.png"}) EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream png(out / "study.png", std::ios::binary);
  char magic[4] = {};
  png.read(magic, 4);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");

  const nlohmann::json j = nlohmann::json::parse(std::ifstream(out / "study.json"));
  EXPECT_TRUE(j["reference"]["converged"].get<bool>());
  EXPECT_LE(j["reference"]["halving_position_change_max"].get<double>(), 1e-4);
  const double dt_crit = j["stability"]["dt_crit"].get<double>();
  ASSERT_EQ(j["runs"].size(), 6u);  // 2 precisions x 3 dt
  for (const auto& r : j["runs"]) {
    const double dt = r["dt"].get<double>();
    if (dt > dt_crit) {
      // 2 ms is 1.5 x dt_crit (1.37 ms): stopped by the blow-up check.
      EXPECT_FALSE(r["stable"].get<bool>()) << r.dump();
      EXPECT_NE(r["reason"].get<std::string>().find("run stopped at t = "), std::string::npos);
      continue;
    }
    EXPECT_TRUE(r["stable"].get<bool>()) << r.dump();
    // A 5 mm push on a 6.9 cm diagonal: errors of a few 1e-4 of the diagonal
    // at these steps; 1e-2 would mean a wrong comparison.
    EXPECT_GT(r["position_error_rms"].get<double>(), 0.0);
    EXPECT_LT(r["position_error_max"].get<double>(), 1e-2);
    EXPECT_LT(r["force_error_rms"].get<double>(), 5e-2);
    EXPECT_GT(r["wall_seconds_per_simulated_second"].get<double>(), 0.0);
  }
  // Halving dt halves the error (first order: the backward-difference damper
  // and the per-tick tool path); at least a 1.5x drop, double precision.
  const auto& a = j["runs"][1];  // double, 0.5 ms
  const auto& b = j["runs"][2];  // double, 0.25 ms
  EXPECT_GT(a["position_error_rms"].get<double>(), 1.5 * b["position_error_rms"].get<double>());
}

// A tick of 2 ms (dt 0.4 ms x 5) lets `--dt 0.002` run as one 2 ms step per
// tick, 1.46 x dt_crit (1.37 ms): the configuration really exceeds dt_crit.
// (With the scenario's 1 ms tick, --dt 0.002 is rounded to the 1 ms tick,
// which is stable, so the unstable branch above never runs.)
// gentle_push.json with a tick of 2 ms (dt 0.4 ms x 5) and `duration`, as
// OUT/long_tick.json (OUT emptied first).
void write_long_tick_scenario(const fs::path& out, double duration) {
  fs::remove_all(out);
  fs::create_directories(out);
  const fs::path stress = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "stress";
  nlohmann::json scenario = nlohmann::json::parse(std::ifstream(stress / "gentle_push.json"));
  scenario["mesh"]["tet"] = (stress / "box.mesh").string();
  scenario["time"] = {{"duration", duration}, {"dt", 0.0004}, {"substeps", 5}};
  std::ofstream(out / "long_tick.json") << scenario.dump(2);
}

TEST(StudyCli, ConfigurationAboveTheCriticalStepIsReportedUnstableWithItsReason) {
  const fs::path out = fs::path(ORGANSIM_TEST_TMP) / "study_unstable";
  write_long_tick_scenario(out, 0.2);
  std::string output;
  const int code = run("study " + (out / "long_tick.json").string() +
                           " --dt 0.002,0.0005 --precision double --duration 0.2 --threads 1 -o " + out.string(),
                       output);
  ASSERT_EQ(code, 0) << output;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(out / "study.json"));
  const double dt_crit = j["stability"]["dt_crit"].get<double>();
  ASSERT_EQ(j["runs"].size(), 2u);
  const auto& over = j["runs"][0];
  EXPECT_DOUBLE_EQ(over["dt"].get<double>(), 0.002);  // not rounded away
  EXPECT_GT(over["dt"].get<double>(), dt_crit);
  EXPECT_TRUE(over["ran"].get<bool>());
  EXPECT_FALSE(over["stable"].get<bool>()) << over.dump();
  EXPECT_NE(over["reason"].get<std::string>().find("run stopped at t = "), std::string::npos) << over.dump();
  const auto& under = j["runs"][1];
  EXPECT_LT(under["dt"].get<double>(), dt_crit);
  EXPECT_TRUE(under["stable"].get<bool>()) << under.dump();
}

// --jobs 3 runs the configurations side by side, each with its share of the
// CPUs: every error, flag and reason equals the serial one-thread study's to
// the last bit (the runs are pure functions of their configuration and the
// backends' results do not depend on the thread count). Wall times, and the
// Pareto front drawn from them, differ and are not compared. The long-tick
// scenario gives an unstable configuration too.
TEST(StudyCli, JobsGiveTheSerialStudysResults) {
  const fs::path out = fs::path(ORGANSIM_TEST_TMP) / "study_jobs";
  write_long_tick_scenario(out, 0.05);
  nlohmann::json study[2];
  for (const int jobs : {1, 3}) {
    const fs::path dir = out / ("jobs_" + std::to_string(jobs));
    std::string output;
    const int code = run("study " + (out / "long_tick.json").string() +
                             " --dt 0.002,0.0005,0.00025 --precision double,float -o " + dir.string() +
                             (jobs == 1 ? " --threads 1" : " --jobs 3"),
                         output);
    ASSERT_EQ(code, 0) << output;
    study[jobs == 1 ? 0 : 1] = nlohmann::json::parse(std::ifstream(dir / "study.json"));
  }
  EXPECT_EQ(study[0]["reference"], study[1]["reference"]);
  ASSERT_EQ(study[0]["runs"].size(), 6u);
  ASSERT_EQ(study[1]["runs"].size(), 6u);
  int unstable = 0;
  for (size_t i = 0; i < 6; ++i) {
    nlohmann::json a = study[0]["runs"][i], b = study[1]["runs"][i];
    for (const char* timing : {"wall_seconds_per_simulated_second", "steps_per_second", "pareto", "device"}) {
      a.erase(timing);
      b.erase(timing);
    }
    EXPECT_EQ(a, b) << "run " << i;
    unstable += !a["stable"].get<bool>();
  }
  EXPECT_EQ(unstable, 2);  // 2 ms in both precisions
}

}  // namespace
