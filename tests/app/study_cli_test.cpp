// `organsim study` end to end on the small gentle-push box: the reference
// converges, a dt above dt_crit is reported unstable with its reason, stable
// runs have small errors that shrink with dt, and the three files are there
// (the plot read back by its pixels: each run where its numbers say);
// sharded, collected, it gives the same table.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#ifdef ORGANSIM_TEST_PLOT_PIXELS
#include "tests/app/plot_pixels.h"
#endif

namespace study_cli_test {
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

#ifdef ORGANSIM_TEST_PLOT_PIXELS
// study.png read back by its pixels (app/study_tables.cpp draws it): inside
// the black frame, x is log10 of wall seconds per simulated second and y
// log10 of the RMS position error, each axis spanning the whole decades
// around the stable runs (at least one); every stable run is a filled disc
// of radius 5 in its series' colour (the series in order of first
// appearance: (200, 80, 30) BGR, then (30, 140, 230)), ringed in black at
// radius 10 on the Pareto front. Checked: a disc of the run's colour where
// its two numbers put it (the plot truncates to whole pixels), no disc of a
// series' colour anywhere else in the frame, and the ring exactly around
// the Pareto runs. A disc that a later run's disc of another series covers
// (centres within 11 px) is not looked for.
void expect_study_plot_shows_the_runs(const fs::path& png, const nlohmann::json& study) {
  const cv::Mat img = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << png;
  const cv::Scalar black(0, 0, 0), colours[] = {{200, 80, 30}, {30, 140, 230}};
  const cv::Rect frame = organsim::test::find_frame(img, black);
  ASSERT_GT(frame.width, 200);
  ASSERT_GT(frame.height, 200);
  struct Run {
    double lx, ly;
    size_t series;
    bool pareto;
    cv::Point2d at;
  };
  std::vector<Run> runs;
  std::vector<std::string> series;
  for (const auto& r : study["runs"]) {
    if (!r["stable"].get<bool>() || !(r["position_error_rms"].get<double>() > 0)) continue;
    const std::string integrator = r["integrator"].get<std::string>();
    const std::string name = (integrator == "verlet" ? "" : integrator + " ") + r["backend"].get<std::string>() +
                             " " + r["precision"].get<std::string>();
    const auto it = std::find(series.begin(), series.end(), name);
    if (it == series.end()) series.push_back(name);
    runs.push_back({std::log10(r["wall_seconds_per_simulated_second"].get<double>()),
                    std::log10(r["position_error_rms"].get<double>()),
                    static_cast<size_t>(std::find(series.begin(), series.end(), name) - series.begin()),
                    r["pareto"].get<bool>(), {}});
  }
  ASSERT_GE(runs.size(), 2u);
  ASSERT_LE(series.size(), 2u);
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const Run& r : runs) x0 = std::min(x0, r.lx), x1 = std::max(x1, r.lx), y0 = std::min(y0, r.ly), y1 = std::max(y1, r.ly);
  x0 = std::floor(x0), x1 = std::max(std::ceil(x1), x0 + 1), y0 = std::floor(y0), y1 = std::max(std::ceil(y1), y0 + 1);
  for (Run& r : runs)
    r.at = {frame.x + (r.lx - x0) / (x1 - x0) * frame.width, frame.y + frame.height - (r.ly - y0) / (y1 - y0) * frame.height};
  auto covered = [&](size_t i) {
    for (size_t j = i + 1; j < runs.size(); ++j)
      if (runs[j].series != runs[i].series && cv::norm(runs[j].at - runs[i].at) < 11) return true;
    return false;
  };
  for (size_t s = 0; s < series.size(); ++s) {
    // Every disc of the series' colour (lines and text opened away) is one
    // of its runs'. Rings, the front's line and the labels drawn over a
    // disc move its visible part's centre by up to ~4 px, a disc covered by
    // another series' by up to ~8.
    const std::vector<cv::Point2d> found =
        organsim::test::blobs(organsim::test::colour_mask(img, colours[s], 8, frame, 3), 12, 6);
    // A series whose every disc another series' covers (double and float
    // at the same dt and nearly the same cost) shows none: only a series
    // with an uncovered disc must be seen.
    bool uncovered = false;
    for (size_t i = 0; i < runs.size(); ++i) uncovered |= runs[i].series == s && !covered(i);
    if (uncovered) {
      EXPECT_FALSE(found.empty()) << series[s];
    }
    for (const cv::Point2d& b : found) {
      bool expected = false;
      for (size_t i = 0; i < runs.size(); ++i)
        expected |= runs[i].series == s && cv::norm(b - runs[i].at) < (covered(i) ? 10 : 6);
      EXPECT_TRUE(expected) << series[s] << ": a disc at (" << b.x << ", " << b.y << ") px where no run is";
    }
  }
  // Every run's disc is where its numbers put it: at least a quarter of the
  // disc (81 px) in its colour within 5 px of that point.
  for (size_t i = 0; i < runs.size(); ++i) {
    if (covered(i)) continue;
    int in_colour = 0;
    for (int dy = -5; dy <= 5; ++dy)
      for (int dx = -5; dx <= 5; ++dx) {
        const int x = static_cast<int>(std::lround(runs[i].at.x)) + dx, y = static_cast<int>(std::lround(runs[i].at.y)) + dy;
        if (dx * dx + dy * dy <= 25 && organsim::test::near_colour(img.at<cv::Vec3b>(y, x), colours[runs[i].series], 8))
          ++in_colour;
      }
    EXPECT_GE(in_colour, 20) << series[runs[i].series] << ": no disc at (" << runs[i].at.x << ", " << runs[i].at.y << ") px";
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    const double ring = organsim::test::ring_share(img, runs[i].at, 10, black, 60);
    bool near_front = false;
    for (size_t j = 0; j < runs.size(); ++j) near_front |= j != i && runs[j].pareto && cv::norm(runs[j].at - runs[i].at) < 24;
    if (runs[i].pareto) {
      EXPECT_GT(ring, 0.5) << "run " << i << " on the Pareto front has no ring";
    } else if (!near_front) {
      EXPECT_LT(ring, 0.3) << "run " << i << " off the Pareto front is ringed";
    }
  }
}
#endif

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
#ifdef ORGANSIM_TEST_PLOT_PIXELS
  expect_study_plot_shows_the_runs(out / "study.png", j);
#endif
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

// The integrator as an axis: Verlet at steps below dt_crit and implicit
// Euler at steps above it, in one table against the same Verlet reference;
// the implicit rows run on the CPU in double, stable beyond dt_crit; the
// Pareto flag is taken across both integrators (a row is on the front when
// no row of either integrator is at least as good in cost and error and
// better in one).
TEST(StudyCli, IntegratorsSideBySideShareTheReferenceAndOneParetoFront) {
  const fs::path out = fs::path(ORGANSIM_TEST_TMP) / "study_integrators";
  fs::remove_all(out);
  fs::create_directories(out);
  // gentle_push.json with a 4 ms tick, so that steps beyond its dt_crit
  // (1.37 ms) fit in a tick.
  const fs::path stress = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "stress";
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(stress / "gentle_push.json"));
  scene["mesh"]["tet"] = (stress / "box.mesh").string();
  scene["time"] = {{"duration", 0.2}, {"dt", 0.0002}, {"substeps", 20}};
  std::ofstream(out / "scene.json") << scene.dump(2);
  std::string output;
  const int code = run("study " + (out / "scene.json").string() + " --integrator verlet,implicit_euler --dt 0.0005,0.00025 "
                           "--implicit-dt 0.004,0.002 --precision double --duration 0.1 --threads 1 -o " + out.string(),
                       output);
  ASSERT_EQ(code, 0) << output;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(out / "study.json"));
  EXPECT_EQ(j["reference"]["integrator"], "verlet");
  const double dt_crit = j["stability"]["dt_crit"].get<double>();
  ASSERT_EQ(j["runs"].size(), 4u);
  std::vector<double> cost, error;
  for (size_t i = 0; i < 4; ++i) {
    const auto& r = j["runs"][i];
    ASSERT_TRUE(r["stable"].get<bool>()) << r.dump();
    EXPECT_EQ(r["integrator"], i < 2 ? "verlet" : "implicit_euler");
    EXPECT_EQ(r["precision"], "double");
    if (i >= 2) {
      EXPECT_GT(r["dt"].get<double>(), dt_crit) << r.dump();
    }
    // The implicit rows' error: numerical damping of a gentle push, a few
    // 1e-3 of the diagonal at most; 1e-2 would mean a wrong comparison.
    EXPECT_LT(r["position_error_max"].get<double>(), 1e-2) << r.dump();
    cost.push_back(r["wall_seconds_per_simulated_second"].get<double>());
    error.push_back(r["position_error_rms"].get<double>());
  }
  for (size_t i = 0; i < 4; ++i) {
    bool dominated = false;
    for (size_t k = 0; k < 4; ++k)
      dominated |= k != i && cost[k] <= cost[i] && error[k] <= error[i] && (cost[k] < cost[i] || error[k] < error[i]);
    EXPECT_EQ(j["runs"][i]["pareto"].get<bool>(), !dominated) << "run " << i;
  }
  std::ifstream csv_file(out / "study.csv");
  const std::string csv((std::istreambuf_iterator<char>(csv_file)), std::istreambuf_iterator<char>());
  EXPECT_EQ(csv.rfind("integrator,backend,precision,dt_s,", 0), 0u) << csv;
  EXPECT_NE(csv.find("\nimplicit_euler,cpu,double,0.004,1,"), std::string::npos) << csv;
#ifdef ORGANSIM_TEST_PLOT_PIXELS
  expect_study_plot_shows_the_runs(out / "study.png", j);
#endif
}

// study.csv with the timing columns (wall_s_per_sim_s, steps_per_s and the
// Pareto flag drawn from them) blanked: what must not depend on the run.
std::string csv_without_timing(const fs::path& file) {
  std::ifstream in(file);
  std::string line, out;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::istringstream fields(line);
    std::string cell;
    for (int column = 0; column < 13 && std::getline(fields, cell, ','); ++column) cells.push_back(cell);
    std::getline(fields, cell);  // the 14th, the reason, may hold commas
    cells.push_back(cell);
    if (cells.size() != 14) return "a line without 14 columns: " + line;
    for (const int timing : {7, 8, 12}) cells[timing].clear();
    for (const std::string& c : cells) out += c + ",";
    out += "\n";
  }
  return out;
}

nlohmann::json without_timing(nlohmann::json study) {
  for (auto& r : study["runs"])
    for (const char* timing : {"wall_seconds_per_simulated_second", "steps_per_second", "pareto"}) r.erase(timing);
  return study;
}

// The reference written once (--reference-only), shards 0/3, 1/3 and 2/3 run
// as separate processes, and --collect: study.json equals the local study's
// but for the timing entries (wall time, steps per second, the Pareto flag
// drawn from them), every other number to the last bit (the shards read the
// reference's exact values back), and study.csv line for line with the
// timing columns blanked. The long-tick scenario gives unstable
// configurations too.
TEST(StudyCli, ShardsCollectedGiveTheLocalTable) {
  const fs::path out = fs::path(ORGANSIM_TEST_TMP) / "study_shards";
  write_long_tick_scenario(out, 0.05);
  const std::string study = "study " + (out / "long_tick.json").string() +
                            " --dt 0.002,0.0005,0.00025 --precision double,float --threads 1 -o ";
  const fs::path local = out / "local", sharded = out / "sharded";
  std::string output;
  ASSERT_EQ(run(study + local.string(), output), 0) << output;
  ASSERT_EQ(run(study + sharded.string() + " --reference-only", output), 0) << output;
  EXPECT_FALSE(fs::exists(sharded / "study.json"));  // no configuration ran
  for (const char* shard : {"0/3", "1/3", "2/3"}) {
    // Before the last shard the table is incomplete: --collect says which are missing.
    std::string collected;
    EXPECT_EQ(run("study --collect " + sharded.string(), collected), 8) << collected;
    EXPECT_NE(collected.find("no outcome yet for configurations"), std::string::npos) << collected;
    ASSERT_EQ(run(study + sharded.string() + " --shard " + shard, output), 0) << output;
  }
  ASSERT_EQ(run("study --collect " + sharded.string(), output), 0) << output;

  const nlohmann::json a = nlohmann::json::parse(std::ifstream(local / "study.json"));
  const nlohmann::json b = nlohmann::json::parse(std::ifstream(sharded / "study.json"));
  ASSERT_EQ(a["runs"].size(), 6u);
  EXPECT_EQ(without_timing(a), without_timing(b));
  EXPECT_EQ(csv_without_timing(local / "study.csv"), csv_without_timing(sharded / "study.csv"));
  EXPECT_TRUE(fs::exists(sharded / "study.png"));
}

// A shard index out of range is refused before anything runs or is written;
// a shard without the reference step, or with other arguments than it had,
// is refused naming the plan and what differs.
TEST(StudyCli, BadShardsAreRefusedBeforeAnyRun) {
  const fs::path out = fs::path(ORGANSIM_TEST_TMP) / "study_bad_shards";
  write_long_tick_scenario(out, 0.02);
  const std::string study =
      "study " + (out / "long_tick.json").string() + " --precision double --threads 1 -o " + (out / "s").string();
  std::string output;
  EXPECT_EQ(run(study + " --dt 0.0005 --shard 3/3", output), 2) << output;
  EXPECT_NE(output.find("--shard: 3/3: shard index 3 out of range 0..2"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(out / "s"));
  output.clear();
  EXPECT_EQ(run(study + " --dt 0.0005 --shard 0/2", output), 3) << output;
  EXPECT_NE(output.find("study_plan.json: no such file: run the same study with --reference-only first"),
            std::string::npos)
      << output;
  ASSERT_EQ(run(study + " --dt 0.0005 --reference-only", output), 0) << output;
  output.clear();
  EXPECT_EQ(run(study + " --dt 0.00025 --shard 0/2", output), 2) << output;
  EXPECT_NE(output.find("the reference was written for other --dt (it has [0.0005])"), std::string::npos) << output;
  EXPECT_TRUE(fs::is_empty(out / "s" / "study_runs"));
}

}  // namespace
}  // namespace study_cli_test
