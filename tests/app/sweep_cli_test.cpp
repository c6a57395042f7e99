// `organsim sweep` end to end on the 125-point box of gentle_push.json, 50
// ticks per case: a failing case is recorded while the others finish and
// --retry-failed reruns only it; a sweep interrupted by SIGINT and rerun
// equals an uninterrupted one; shards 0/3, 1/3, 2/3 collected equal the
// local run, force logs byte for byte.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "tests/app/run_cli_test_util.h"
#ifdef ORGANSIM_TEST_PLOT_PIXELS
#include "tests/app/plot_pixels.h"
#endif

extern char** environ;

namespace organsim::test {
namespace sweep_cli_test {
namespace {

namespace fs = std::filesystem;

fs::path tmp(const std::string& name) { return fs::path(ORGANSIM_TEST_TMP) / "sweep" / name; }

// Six cases (3 stiffnesses x 2 push depths) of 50 ticks on the box; with
// `unstable`, a seventh whose dt is above dt_crit (1.37 ms), which `run`
// refuses with exit 5.
fs::path write_sweep(const fs::path& dir, bool unstable = false) {
  fs::create_directories(dir);
  nlohmann::json j = {
      {"scenario", std::string(ORGANSIM_SOURCE_DIR) + "/scenarios/stress/gentle_push.json"},
      {"set", {{"time.duration", 0.05}, {"tool.keyframes[1].t", 0.05}}},
      {"grid", {{"material.young_modulus", {4000, 6000, 8000}}, {"tool.keyframes[1].position[2]", {0.046, 0.044}}}}};
  if (unstable) {
    j.erase("grid");
    j["cases"] = {{{"name", "soft"}, {"material.young_modulus", 4000}},
                  {{"name", "unstable"}, {"time.dt", 0.002}, {"time.substeps", 1}},
                  {{"name", "stiff"}, {"material.young_modulus", 8000}}};
  }
  std::ofstream(dir / "sweep.json") << j.dump(2);
  return dir / "sweep.json";
}

// "sweep 'SWEEP' -o 'OUT' EXTRA" (appended: gcc 12 warns falsely, -Wrestrict, on "literal" + string).
std::string sweep_cmd(const fs::path& sweep, const fs::path& out, const std::string& extra = "") {
  std::string s("sweep '");
  s.append(sweep.string()).append("' -o '").append(out.string()).append("' ").append(extra);
  return s;
}

nlohmann::json read_json(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }

// results.json without the timing (wall time, real-time factor), which
// differs between any two runs; everything else is a function of the scenarios.
nlohmann::json results_without_timing(const fs::path& outdir) {
  nlohmann::json rows = read_json(outdir / "results.json");
  for (auto& row : rows) row.erase("timing");
  return rows;
}

// The force log's samples as written (the meta has the run's timings).
std::string samples_text(const fs::path& forces) {
  const std::string text = slurp(forces);
  const size_t at = text.find("\n \"samples\": {");
  EXPECT_NE(at, std::string::npos) << forces;
  return at == std::string::npos ? std::string() : text.substr(at);
}

void expect_same_sweep(const fs::path& a, const fs::path& b) {
  const nlohmann::json ra = results_without_timing(a), rb = results_without_timing(b);
  EXPECT_EQ(ra, rb) << ra.dump(1) << "\n---\n" << rb.dump(1);
  for (const auto& row : ra) {
    const std::string name = row["name"];
    const std::string sa = samples_text(a / "cases" / name / "forces.json");
    EXPECT_FALSE(sa.empty());
    EXPECT_TRUE(sa == samples_text(b / "cases" / name / "forces.json")) << name << ": force samples differ";
  }
}

// One uninterrupted local sweep that several tests compare against. ctest
// runs each test in its own process, two at a time: the first to take the
// lock runs it, the others find it done (a rerun of a finished sweep runs
// nothing). The folder is per build of organsim, so a rebuilt executable
// never meets an old reference.
fs::path reference_sweep() {
  const auto built = fs::last_write_time(ORGANSIM_EXE).time_since_epoch().count();
  const fs::path dir = tmp(std::string("reference-").append(std::to_string(built)));
  fs::create_directories(dir);
  const int lock = open((dir / "lock").c_str(), O_CREAT | O_RDWR, 0644);
  EXPECT_GE(lock, 0);
  flock(lock, LOCK_EX);
  const fs::path manifest = dir / "out" / "manifest.json";
  if (!fs::exists(manifest) || read_json(manifest)["counts"]["done"] != 6) {
    const fs::path sweep = write_sweep(dir);
    const CliResult r = run_organsim(sweep_cmd(sweep, dir / "out", "--at 0.02,0.05"), dir);
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  }
  flock(lock, LOCK_UN);
  close(lock);
  return dir / "out";
}

#ifdef ORGANSIM_TEST_PLOT_PIXELS
// results.png read back by its pixels (app/sweep_collect.cpp, drawn by
// core/render/xy_plot.cpp): peak_force against the first swept field
// (material.young_modulus), one line per value of the other (the push's
// end height, position2), the lines in the order of their names
// ("position2=0.044", "position2=0.046"), coloured (200, 80, 30) and
// (30, 140, 230) BGR, joining the cases in order of E. Read per column:
// each line's row (the mean row of its colour there). A line runs from its
// smallest E to its largest, so its first and last columns place E; the
// rows at the cases' columns must then lie on one linear map of the peak
// force, the same for both lines, growing upwards, and between the cases
// each line must be straight. Within 1.5 px: the plot rounds to whole
// pixels and the line's end is clipped at the frame. A swapped or flipped
// axis, or a line drawn with another line's numbers, leaves the map.
void expect_results_plot_shows_the_cases(const fs::path& png, const nlohmann::json& rows) {
  const cv::Mat img = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << png;
  const cv::Rect frame = find_frame(img, cv::Scalar(30, 30, 30));
  ASSERT_GT(frame.width, 200);
  ASSERT_GT(frame.height, 200);
  const cv::Scalar colours[] = {{200, 80, 30}, {30, 140, 230}};
  const double heights[] = {0.044, 0.046};
  std::vector<double> force, row;
  for (int s = 0; s < 2; ++s) {
    std::vector<std::pair<double, double>> cases;  // (E, peak force) of this line, by E
    for (const auto& r : rows)
      if (r["overrides"]["tool.keyframes[1].position[2]"].get<double>() == heights[s])
        cases.push_back({r["overrides"]["material.young_modulus"].get<double>(), r["figures"]["peak_force"].get<double>()});
    std::sort(cases.begin(), cases.end());
    ASSERT_EQ(cases.size(), 3u) << "line " << s;
    const std::vector<double> at = curve_rows(img, colours[s], 8, frame);
    int first = -1, last = -1;
    for (int c = 0; c < static_cast<int>(at.size()); ++c)
      if (!std::isnan(at[c])) (first < 0 ? first : last) = c;
    ASSERT_GE(first, 0) << "line " << s << " is not in the plot";
    ASSERT_GT(last - first, frame.width / 2) << "line " << s << " spans " << last - first << " px";
    const double e0 = cases.front().first, e1 = cases.back().first;
    auto column_of = [&](double e) { return first + (e - e0) / (e1 - e0) * (last - first); };
    for (const auto& [e, f] : cases) {
      const int c = static_cast<int>(std::lround(column_of(e)));
      ASSERT_FALSE(std::isnan(at[c])) << "line " << s << " has no pixel at E = " << e;
      force.push_back(f), row.push_back(at[c]);
    }
    // Straight between the cases: every column within 1.5 px of the chord.
    for (size_t i = 0; i + 1 < cases.size(); ++i) {
      const double c0 = column_of(cases[i].first), c1 = column_of(cases[i + 1].first);
      const double r0 = at[static_cast<int>(std::lround(c0))], r1 = at[static_cast<int>(std::lround(c1))];
      for (int c = static_cast<int>(std::ceil(c0)) + 5; c < c1 - 5; ++c)  // clear of the markers
        if (!std::isnan(at[c])) {
          EXPECT_NEAR(at[c], r0 + (c - c0) / (c1 - c0) * (r1 - r0), 1.5) << "line " << s << ", column " << c;
        }
    }
  }
  const LineFit y = fit_line(force, row);
  EXPECT_LT(y.b, 0) << "the force grows upwards";
  EXPECT_LT(y.worst, 1.5) << "a case off the force axis' map by " << y.worst << " px";
}
#endif

TEST(SweepCli, LocalSweepWritesEveryCaseManifestAndResults) {
  const fs::path out = reference_sweep();
  const nlohmann::json manifest = read_json(out / "manifest.json");
  EXPECT_EQ(manifest["counts"]["done"], 6);
  EXPECT_EQ(manifest["counts"]["pending"], 0);
  ASSERT_EQ(manifest["cases"].size(), 6u);
  EXPECT_EQ(manifest["cases"][0]["name"], "young_modulus=4000,position2=0.046");
  EXPECT_EQ(manifest["cases"][0]["exit_code"], 0);
  EXPECT_EQ(manifest["cases"][0]["meta"]["samples"], 50);
  EXPECT_GT(manifest["cases"][0]["meta"]["dt_crit"].get<double>(), 0.0);

  const nlohmann::json rows = read_json(out / "results.json");
  ASSERT_EQ(rows.size(), 6u);
  // Each row's figures come from its own force log.
  for (const auto& row : rows) {
    const nlohmann::json log = read_json(out / "cases" / row["name"].get<std::string>() / "forces.json");
    double peak = 0;
    for (const auto& f : log["samples"]["force"])
      peak =
          std::max(peak, std::sqrt(f[0].get<double>() * f[0].get<double>() + f[1].get<double>() * f[1].get<double>() +
                                   f[2].get<double>() * f[2].get<double>()));
    EXPECT_EQ(row["figures"]["peak_force"].get<double>(), peak) << row.dump();
    EXPECT_EQ(row["figures"]["dt_crit"], log["meta"]["dt_crit"]);
  }
  // The physics shows through: a stiffer box and a deeper push give a larger
  // peak force (same depth, E 4000 -> 8000 Pa; same E, 4 -> 6 mm).
  EXPECT_GT(rows[4]["figures"]["peak_force"].get<double>(), rows[0]["figures"]["peak_force"].get<double>());
  EXPECT_GT(rows[1]["figures"]["peak_force"].get<double>(), rows[0]["figures"]["peak_force"].get<double>());
  EXPECT_FALSE(rows[0]["figures"]["force_at_0.02"].is_null());

  const std::string csv = slurp(out / "results.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "case,status,material.young_modulus,tool.keyframes[1].position[2],peak_force,peak_force_t,force_at_0.02,"
            "force_at_0.05,dt_crit,completed,stop_reason,samples,real_time_factor,wall_seconds,error");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 7);
  std::ifstream png(out / "results.png", std::ios::binary);
  char magic[4] = {};
  png.read(magic, 4);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
#ifdef ORGANSIM_TEST_PLOT_PIXELS
  expect_results_plot_shows_the_cases(out / "results.png", rows);
#endif
}

TEST(SweepCli, RerunSkipsDoneCases) {
  const fs::path dir = tmp("rerun");
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy(reference_sweep(), dir / "out", fs::copy_options::recursive);
  const fs::path sweep = write_sweep(dir);
  const std::string before = slurp(dir / "out" / "cases" / "young_modulus=4000,position2=0.046" / "status.json");
  const CliResult r = run_organsim(sweep_cmd(sweep, dir / "out"), dir);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("6 done, 0 failed (skipped), 0 to run"), std::string::npos) << r.out;
  EXPECT_EQ(slurp(dir / "out" / "cases" / "young_modulus=4000,position2=0.046" / "status.json"), before);
}

TEST(SweepCli, FailingCaseIsRecordedOthersFinishRetryRerunsOnlyIt) {
  const fs::path dir = tmp("failing");
  fs::remove_all(dir);
  const fs::path sweep = write_sweep(dir, true);
  const fs::path out = dir / "out";
  CliResult r = run_organsim(sweep_cmd(sweep, out, "--jobs 2"), dir);
  EXPECT_EQ(r.exit_code, 8) << r.out << r.err;  // some cases failed
  EXPECT_NE(r.err.find("1 of 3 cases failed"), std::string::npos) << r.err;
  const nlohmann::json m = read_json(out / "manifest.json");
  EXPECT_EQ(m["counts"]["done"], 2);
  EXPECT_EQ(m["counts"]["failed"], 1);
  const nlohmann::json& bad = m["cases"][1];
  EXPECT_EQ(bad["name"], "unstable");
  EXPECT_EQ(bad["status"], "failed");
  EXPECT_EQ(bad["exit_code"], 5);  // ErrorKind::Numerical: dt above dt_crit refused
  EXPECT_NE(bad["error"].get<std::string>().find("dt_crit"), std::string::npos) << bad.dump();
  EXPECT_EQ(m["cases"][2]["status"], "done");

  const std::string soft_status = slurp(out / "cases" / "soft" / "status.json");
  const auto unstable_log_time = fs::last_write_time(out / "cases" / "unstable" / "run.log");
  // Without --retry-failed nothing runs; with it, only the failed case.
  r = run_organsim(sweep_cmd(sweep, out), dir);
  EXPECT_EQ(r.exit_code, 8);
  EXPECT_NE(r.out.find("2 done, 1 failed (skipped; --retry-failed reruns them), 0 to run"), std::string::npos) << r.out;
  EXPECT_EQ(fs::last_write_time(out / "cases" / "unstable" / "run.log"), unstable_log_time);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // a rewritten log gets a later time
  r = run_organsim(sweep_cmd(sweep, out, "--retry-failed"), dir);
  EXPECT_EQ(r.exit_code, 8);
  EXPECT_NE(r.out.find("2 done, 0 failed (skipped), 1 to run"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("[1/1] unstable: failed"), std::string::npos) << r.out;
  EXPECT_GT(fs::last_write_time(out / "cases" / "unstable" / "run.log"), unstable_log_time);
  EXPECT_EQ(slurp(out / "cases" / "soft" / "status.json"), soft_status);  // not rerun: same wall time recorded
}

pid_t spawn_organsim(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> argv{ORGANSIM_EXE};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> c;
  for (auto& a : argv) c.push_back(a.data());
  c.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, 1, 2);
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, c[0], &files, nullptr, c.data(), environ), 0);
  posix_spawn_file_actions_destroy(&files);
  return pid;
}

int count_status_files(const fs::path& out) {
  int n = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out / "cases", ec)) n += fs::exists(e.path() / "status.json");
  return n;
}

TEST(SweepCli, InterruptedSweepRerunEqualsAnUninterruptedOne) {
  const fs::path dir = tmp("interrupted");
  fs::remove_all(dir);
  const fs::path sweep = write_sweep(dir);
  const fs::path out = dir / "out";
  // One case at a time; SIGINT once two cases are recorded.
  const pid_t pid = spawn_organsim({"sweep", sweep.string(), "-o", out.string(), "--jobs", "1", "--at", "0.02,0.05"},
                                   dir / "first.log");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (count_status_files(out) < 2 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_EQ(kill(pid, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  const std::string first = slurp(dir / "first.log");
  ASSERT_TRUE(WIFEXITED(status)) << first;
  ASSERT_EQ(WEXITSTATUS(status), 130) << "the sweep finished before the signal; the cases are too short:\n" << first;
  EXPECT_NE(first.find("interrupted: "), std::string::npos) << first;

  const nlohmann::json m = read_json(out / "manifest.json");
  const int done = m["counts"]["done"], pending = m["counts"]["pending"];
  EXPECT_GE(done, 2);
  EXPECT_GE(pending, 1);
  EXPECT_EQ(done + pending, 6);
  // The run stopped mid-case has no status, hence is not done, and left no process.
  EXPECT_EQ(count_status_files(out), done);

  const CliResult r = run_organsim(sweep_cmd(sweep, out, "--at 0.02,0.05"), dir);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find(std::to_string(done) + " done, 0 failed (skipped), " + std::to_string(pending) + " to run"),
            std::string::npos)
      << r.out;
  expect_same_sweep(out, reference_sweep());
}

TEST(SweepCli, ShardsCollectedEqualTheLocalRun) {
  const fs::path dir = tmp("shards");
  fs::remove_all(dir);
  const fs::path sweep = write_sweep(dir);
  const fs::path out = dir / "out";
  for (int i = 0; i < 3; ++i) {
    const CliResult r = run_organsim(
        sweep_cmd(sweep, out, std::string("--shard ").append(std::to_string(i)).append("/3")), dir / std::to_string(i));
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_NE(r.out.find(std::string("shard ").append(std::to_string(i)).append("/3: 2 cases")), std::string::npos)
        << r.out;
    EXPECT_FALSE(fs::exists(out / "results.json"));  // shards leave the merging to --collect
  }
  const CliResult r =
      run_organsim(std::string("sweep --collect '").append(out.string()).append("' --at 0.02,0.05"), dir);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  expect_same_sweep(out, reference_sweep());
  EXPECT_EQ(read_json(out / "manifest.json")["counts"]["done"], 6);
}

TEST(SweepCli, BadShardAndBadSweepRunNothing) {
  const fs::path dir = tmp("refused");
  fs::remove_all(dir);
  const fs::path sweep = write_sweep(dir);
  CliResult r = run_organsim(sweep_cmd(sweep, dir / "out", "--shard 3/3"), dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--shard: 3/3: shard index 3 out of range 0..2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));

  nlohmann::json j = read_json(sweep);
  j["grid"]["material.young_modulus"][2] = "stiff";
  std::ofstream(sweep) << j.dump();
  r = run_organsim(sweep_cmd(sweep, dir / "out"), dir);
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(
      r.err.find(
          R"(material.young_modulus: expected a number, got a string (set by grid["material.young_modulus"][2]))"),
      std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// --collect reads back files any process or person may have touched: a
// force log or a plan that is not one stops it with exit 3 naming the file
// and the entry, before it writes anything (the last collection's files stay).
TEST(SweepCli, CollectRefusesAForceLogOrPlanThatIsNotOneAndWritesNothing) {
  const fs::path dir = tmp("collect_refused");
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path out = dir / "out";
  fs::copy(reference_sweep(), out, fs::copy_options::recursive);
  const std::string collect = std::string("sweep --collect '").append(out.string()).append("'");
  const fs::path log = out / "cases" / "young_modulus=6000,position2=0.044" / "forces.json";
  nlohmann::json j = read_json(log);
  j["samples"]["force"][7] = {0.5};  // one component: reading on would run past the array
  std::ofstream(log) << j.dump();
  // Files a collection would write anew, in another layout than it writes them.
  for (const char* f : {"results.json", "manifest.json"}) {
    const std::string relaid = read_json(out / f).dump(4);
    std::ofstream(out / f) << relaid;
  }
  const std::string results = slurp(out / "results.json"), manifest = slurp(out / "manifest.json");
  CliResult r = run_organsim(collect, dir);
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find(log.string() + ": samples.force[7]: expected three numbers or nulls (N)"), std::string::npos)
      << r.err;
  EXPECT_EQ(slurp(out / "results.json"), results);
  EXPECT_EQ(slurp(out / "manifest.json"), manifest);

  nlohmann::json plan = read_json(out / "cases.json");
  plan["cases"][2]["name"] = "../../elsewhere";
  std::ofstream(out / "cases.json") << plan.dump();
  r = run_organsim(collect, dir);
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find((out / "cases.json").string() + ": cases[2].name: a case name must not start with '.' or '-'"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(slurp(out / "manifest.json"), manifest);
}

TEST(SweepCli, SlurmScriptForTheSweep) {
  const fs::path dir = tmp("slurm_script");
  fs::remove_all(dir);
  const fs::path sweep = write_sweep(dir);
  const CliResult r =
      run_organsim(sweep_cmd(sweep, dir / "out", "--slurm --cases-per-task 2 --max-parallel 2 --time 00:10:00"), dir);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::string script = slurp(dir / "out" / "sweep.sbatch");
  EXPECT_NE(script.find("#SBATCH --array=0-2%2\n"), std::string::npos) << script;
  EXPECT_NE(script.find("--shard slurm"), std::string::npos) << script;
  EXPECT_TRUE(fs::exists(dir / "out" / "cases.json"));
  EXPECT_FALSE(fs::exists(dir / "out" / "cases"));  // nothing ran
}

}  // namespace
}  // namespace sweep_cli_test
}  // namespace organsim::test
