// Shard slices (local and from a Slurm array task's environment), a
// finished run's judgement, the figures collected from a force log, and the
// sweep's files read back (plan, status, force log) refusing what is not one.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "core/sweep/case_names.h"
#include "core/sweep/case_status.h"
#include "core/sweep/shard.h"
#include "core/sweep/slurm_script.h"
#include "core/sweep/sweep_plan.h"
#include "core/sweep/sweep_results.h"
#include "core/util/error.h"

namespace organsim {
namespace sweep_shard_results_test {
namespace {

namespace fs = std::filesystem;

Shard shard_with(const std::string& spec, const std::map<std::string, std::string>& env) {
  return parse_shard(spec, [&](const char* name) -> const char* {
    const auto it = env.find(name);
    return it == env.end() ? nullptr : it->second.c_str();
  });
}

std::string shard_refusal(const std::string& spec, const std::map<std::string, std::string>& env = {}) {
  try {
    shard_with(spec, env);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    return e.what();
  }
  ADD_FAILURE() << "accepted " << spec;
  return {};
}

TEST(SweepShard, SlicesAreDisjointAndCoverEveryCase) {
  std::multiset<size_t> taken;
  for (int i = 0; i < 3; ++i) {
    const Shard s = shard_with(std::to_string(i) + "/3", {});
    for (size_t c = 0; c < 10; ++c) {
      if (s.takes(c)) taken.insert(c);
    }
  }
  ASSERT_EQ(taken.size(), 10u);
  for (size_t c = 0; c < 10; ++c) EXPECT_EQ(taken.count(c), 1u) << c;
}

TEST(SweepShard, SlurmEnvironment) {
  Shard s = shard_with("slurm", {{"SLURM_ARRAY_TASK_ID", "2"}, {"SLURM_ARRAY_TASK_COUNT", "3"}});
  EXPECT_EQ(s.index, 2);
  EXPECT_EQ(s.count, 3);
  // An array 5-7 (no COUNT): index from MIN.
  s = shard_with("slurm", {{"SLURM_ARRAY_TASK_ID", "6"}, {"SLURM_ARRAY_TASK_MIN", "5"}, {"SLURM_ARRAY_TASK_MAX", "7"}});
  EXPECT_EQ(s.index, 1);
  EXPECT_EQ(s.count, 3);
}

TEST(SweepShard, OutOfRangeAndMalformedAreRefused) {
  EXPECT_NE(shard_refusal("3/3").find("shard index 3 out of range 0..2"), std::string::npos);
  EXPECT_NE(shard_refusal("1/0").find("at least 1"), std::string::npos);
  EXPECT_NE(shard_refusal("one/3").find("expected i/N"), std::string::npos);
  EXPECT_NE(shard_refusal("slurm").find("SLURM_ARRAY_TASK_ID is not set"), std::string::npos);
  EXPECT_NE(shard_refusal("slurm", {{"SLURM_ARRAY_TASK_ID", "4"}, {"SLURM_ARRAY_TASK_COUNT", "3"}})
                .find("shard index 4 out of range 0..2"),
            std::string::npos);
}

TEST(SweepSlurmScript, ArrayPacksCasesAndThrottles) {
  SlurmOptions o;
  o.cases_per_task = 4;
  o.max_parallel = 2;
  o.cpus_per_task = 3;
  o.partition = "short";
  o.setup = {"module load gcc/12"};
  EXPECT_EQ(slurm_array_tasks(10, o), 3);
  const std::string s = slurm_script(o, 10, "/opt/organsim/bin/organsim", "/home/u/s.json", "/scratch/u/out");
  EXPECT_NE(s.find("#SBATCH --array=0-2%2\n"), std::string::npos) << s;
  EXPECT_NE(s.find("#SBATCH --cpus-per-task=3\n"), std::string::npos) << s;
  EXPECT_NE(s.find("#SBATCH --partition=short\n"), std::string::npos) << s;
  EXPECT_NE(s.find("module load gcc/12\nexec '/opt/organsim/bin/organsim' sweep '/home/u/s.json' -o '/scratch/u/out' "
                   "--shard slurm --jobs 3\n"),
            std::string::npos)
      << s;
  EXPECT_EQ(shell_quote("it's"), "'it'\\''s'");
}

nlohmann::json force_log(bool completed) {
  // |F| = 0, 5, 13, 1 at t = 0.001 .. 0.004 (tick 1 ms).
  return {{"meta",
           {{"tick", 0.001},
            {"dt_crit", 0.0005},
            {"completed", completed},
            {"stop_reason", completed ? "" : "blow-up"},
            {"real_time_factor", 2.0}}},
          {"samples", {{"t", {0.001, 0.002, 0.003, 0.004}}, {"force", {{0, 0, 0}, {3, 4, 0}, {0, 5, 12}, {1, 0, 0}}}}}};
}

TEST(SweepResults, FiguresOfAForceLog) {
  const ForceLogSummary log = force_log_summary(force_log(true).dump(), "forces.json", {0.0021, 0.004, 0.0044, 0.01});
  const nlohmann::json& f = log.figures;
  EXPECT_EQ(f["peak_force"], 13.0);
  EXPECT_EQ(f["peak_force_t"], 0.003);
  EXPECT_EQ(f[force_at_name(0.0021)], 5.0);  // nearest sample: t = 0.002
  EXPECT_EQ(f[force_at_name(0.004)], 1.0);
  EXPECT_TRUE(f[force_at_name(0.01)].is_null());     // past the last sample by more than half a tick
  EXPECT_FALSE(f[force_at_name(0.0044)].is_null());  // within half a tick of the last
  EXPECT_EQ(f["dt_crit"], 0.0005);
  EXPECT_EQ(f["samples"], 4);
  EXPECT_EQ(log.timing["real_time_factor"], 2.0);
  EXPECT_EQ(log.timing["wall_seconds"], 0.0);  // absent: 0
  EXPECT_EQ(figure_label("peak_force"), "peak_force (N)");
  EXPECT_EQ(figure_label(force_at_name(0.1)), "force_at_0.1 (N)");
  EXPECT_EQ(figure_label("dt_crit"), "dt_crit (s)");
  EXPECT_EQ(figure_label("real_time_factor"), "real_time_factor");
}

// What force_log_summary says of `log`'s text, "" when it accepts it.
std::string force_log_refusal(const nlohmann::json& log) {
  try {
    force_log_summary(log.dump(), "c/forces.json", {0.002});
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    return e.what();
  }
  return "";
}

// A force log that is not one (truncated, edited, from elsewhere) is refused
// naming the file and the entry, never read past its arrays.
TEST(SweepResults, AForceLogThatIsNotOneIsRefusedNamingTheEntry) {
  EXPECT_EQ(force_log_refusal(force_log(true)), "");
  auto changed = [](auto change) {
    nlohmann::json log = force_log(true);
    change(log);
    return force_log_refusal(log);
  };
  EXPECT_EQ(changed([](nlohmann::json& l) { l["samples"]["force"][2] = {5.0}; }),
            "c/forces.json: samples.force[2]: expected three numbers or nulls (N)");
  EXPECT_EQ(changed([](nlohmann::json& l) { l["samples"]["force"][1][0] = "3"; }),
            "c/forces.json: samples.force[1]: expected three numbers or nulls (N)");
  EXPECT_EQ(changed([](nlohmann::json& l) { l["samples"]["t"][3] = nullptr; }),
            "c/forces.json: samples.t[3]: expected a time in s");
  EXPECT_EQ(changed([](nlohmann::json& l) { l["samples"]["t"].erase(3); }),
            "c/forces.json: samples.force: expected one force per time (3)");
  EXPECT_EQ(changed([](nlohmann::json& l) { l["samples"].erase("t"); }),
            "c/forces.json: samples.t: expected a value (missing)");
  EXPECT_EQ(changed([](nlohmann::json& l) { l["meta"] = 1; }), "c/forces.json: file.meta: expected an object");
  EXPECT_EQ(changed([](nlohmann::json& l) { l["meta"]["tick"] = "1 ms"; }),
            "c/forces.json: meta.tick: expected a tick in s");
  EXPECT_EQ(changed([](nlohmann::json& l) { l["meta"]["completed"] = 1; }),
            "c/forces.json: meta.completed: expected true or false");
  // A force written as null (not finite) is accepted and has no magnitude.
  EXPECT_EQ(changed([](nlohmann::json& l) { l["samples"]["force"][1] = {nullptr, nullptr, nullptr}; }), "");
  try {
    force_log_summary("{\"meta\": {", "c/forces.json", {});
    ADD_FAILURE() << "truncated log accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("c/forces.json: invalid JSON: ", 0), 0u) << e.what();
  }
}

Sweep two_case_plan() {
  Sweep plan;
  plan.file = "/s/sweep.json";
  plan.scenario = "/s/base.json";
  plan.swept_paths = {"material.young_modulus"};
  plan.fixed = {{"time.duration", 0.05, "set"}};
  for (int e : {4000, 8000}) {
    SweepCase c;
    c.name = "young_modulus=" + std::to_string(e);
    c.overrides = {{"material.young_modulus", e, ""}};
    c.scenario_hash = text_hash(c.name);
    c.writes_forces = true;
    plan.cases.push_back(c);
  }
  return plan;
}

std::string plan_refusal(const nlohmann::json& plan) {
  try {
    parse_plan(plan.dump(), "out/cases.json");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    return e.what();
  }
  return "";
}

// The plan read back is the plan written (shards and --collect agree on it);
// one that is not a plan is refused naming the entry, and a case name that
// could leave OUTDIR/cases/ or name two cases' folder is refused too.
TEST(SweepPlanFile, ReadBackEqualsWrittenAndBadPlansAreRefusedNamingTheEntry) {
  const nlohmann::json written = plan_json(two_case_plan());
  const Sweep read = parse_plan(written.dump(), "out/cases.json");
  ASSERT_EQ(read.cases.size(), 2u);
  EXPECT_EQ(read.cases[1].name, "young_modulus=8000");
  EXPECT_EQ(read.cases[1].overrides.at(0).value, 8000);
  EXPECT_EQ(plan_json(read), written);

  auto changed = [&](auto change) {
    nlohmann::json j = written;
    change(j);
    return plan_refusal(j);
  };
  EXPECT_EQ(changed([](nlohmann::json& j) { j["cases"][1]["name"] = "../../escape"; }),
            "out/cases.json: cases[1].name: a case name must not start with '.' or '-'");
  EXPECT_EQ(changed([](nlohmann::json& j) { j["cases"][1]["name"] = "a/b"; }),
            "out/cases.json: cases[1].name: a case name may hold letters, digits and . _ - + = , ~ only (it names a "
            "folder)");
  EXPECT_EQ(changed([](nlohmann::json& j) { j["cases"][1]["name"] = j["cases"][0]["name"]; }),
            "out/cases.json: cases[1].name: expected a name no other case has");
  EXPECT_EQ(changed([](nlohmann::json& j) { j["cases"][0]["overrides"] = nullptr; }),
            "out/cases.json: cases[0].overrides: expected an object");
  EXPECT_EQ(changed([](nlohmann::json& j) { j["cases"][0]["writes_forces"] = "yes"; }),
            "out/cases.json: cases[0].writes_forces: expected true or false");
  EXPECT_EQ(changed([](nlohmann::json& j) { j["swept"][0] = 1; }), "out/cases.json: swept[0]: expected a field path");
  EXPECT_EQ(changed([](nlohmann::json& j) { j["scenario"] = ""; }),
            "out/cases.json: scenario: expected the base scenario's path");
  EXPECT_EQ(changed([](nlohmann::json& j) { j.erase("cases"); }),
            "out/cases.json: file.cases: expected a value (missing)");
}

// A failed case's log may be why it failed: its row keeps the error and has
// no figures, and the other rows are collected. A done case's log that is
// not one stops the collection naming it.
TEST(SweepResults, AFailedCasesBrokenLogLeavesItsRowWithoutFiguresADoneCasesStopsTheCollection) {
  const fs::path out = fs::path(ORGANSIM_TEST_TMP) / "sweep_results_broken_log";
  fs::remove_all(out);
  const Sweep plan = two_case_plan();
  nlohmann::json broken = force_log(true);
  broken["samples"]["force"][1] = {3.0, 4.0};
  std::vector<CaseRecord> records(2);
  for (int i = 0; i < 2; ++i) {
    CaseStatus s;
    s.state = records[i].state = i == 0 ? CaseState::Failed : CaseState::Done;
    s.scenario_hash = plan.cases[i].scenario_hash;
    if (i == 0) s.error = "exited 0, but forces.json: samples.force[1]: ...";
    records[i].status = s;
  }
  for (int i = 0; i < 2; ++i) {
    fs::create_directories(case_dir(out, plan.cases[i]));
    std::ofstream(case_dir(out, plan.cases[i]) / "forces.json") << (i == 0 ? broken : force_log(true)).dump();
  }
  const nlohmann::json rows = results_json(plan, records, out, {});
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_TRUE(rows[0]["figures"].is_null());
  EXPECT_EQ(rows[0]["error"], "exited 0, but forces.json: samples.force[1]: ...");
  EXPECT_EQ(rows[1]["figures"]["peak_force"], 13.0);

  std::ofstream(case_dir(out, plan.cases[1]) / "forces.json") << broken.dump();
  try {
    results_json(plan, records, out, {});
    ADD_FAILURE() << "a done case's broken log was collected";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), (case_dir(out, plan.cases[1]) / "forces.json").string() +
                                         ": samples.force[1]: expected three numbers or nulls (N)");
  }
}

// A status file reads back as written; one that is not a status file of a
// finished run reads as none, so its case is run again.
TEST(SweepCaseStatus, AStatusFileThatIsNotOneReadsAsNone) {
  CaseStatus s;
  s.state = CaseState::Failed;
  s.exit_code = 5;
  s.error = "organsim: error: blow-up";
  s.wall_seconds = 1.5;
  s.scenario_hash = "abc";
  s.meta = {{"samples", 3}};
  const nlohmann::json written = to_json(s);
  const std::optional<CaseStatus> read = parse_case_status(written.dump());
  ASSERT_TRUE(read);
  EXPECT_EQ(to_json(*read), written);
  for (auto change : std::vector<void (*)(nlohmann::json&)>{
           [](nlohmann::json& j) { j["status"] = "pending"; },
           [](nlohmann::json& j) { j["exit_code"] = 1e30; },
           [](nlohmann::json& j) { j["exit_code"] = 1.5; },
           [](nlohmann::json& j) { j["wall_seconds"] = "inf"; },
           [](nlohmann::json& j) { j["wall_seconds"] = -1; },
           [](nlohmann::json& j) { j.erase("scenario_hash"); },
           [](nlohmann::json& j) { j = nlohmann::json::array(); },
       }) {
    nlohmann::json j = written;
    change(j);
    EXPECT_FALSE(parse_case_status(j.dump())) << j.dump();
  }
  EXPECT_FALSE(parse_case_status("{\"status\": \"done\""));
}

// A run that exited 0 is done only with a complete force log that --collect can read.
TEST(SweepCaseStatus, JudgeRunNeedsACompleteForceLog) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "sweep_judge";
  fs::remove_all(dir);
  fs::create_directories(dir);
  SweepCase c;
  c.name = "x";
  c.scenario_hash = "abc";
  CaseStatus s = judge_run(c, dir, 0, 0, 1.0, "");
  EXPECT_EQ(s.state, CaseState::Failed);
  EXPECT_EQ(s.error, "exited 0, but forces.json was not written");

  std::ofstream(dir / "forces.json") << force_log(false).dump();
  s = judge_run(c, dir, 0, 0, 1.0, "");
  EXPECT_EQ(s.state, CaseState::Failed);
  EXPECT_NE(s.error.find("stopped early: blow-up"), std::string::npos) << s.error;

  s = judge_run(c, dir, 5, 0, 1.0, "run: ...\norgansim: error: t = 0.1: blow-up\n\n");
  EXPECT_EQ(s.state, CaseState::Failed);
  EXPECT_EQ(s.error, "organsim: error: t = 0.1: blow-up");
  EXPECT_EQ(s.exit_code, 5);

  // A log that --collect would refuse is no complete log either.
  nlohmann::json broken = force_log(true);
  broken["samples"]["force"][1] = {3.0, 4.0};
  std::ofstream(dir / "forces.json") << broken.dump();
  s = judge_run(c, dir, 0, 0, 1.0, "");
  EXPECT_EQ(s.state, CaseState::Failed);
  EXPECT_EQ(s.error, "exited 0, but forces.json: samples.force[1]: expected three numbers or nulls (N)");

  std::ofstream(dir / "forces.json") << force_log(true).dump();
  s = judge_run(c, dir, 0, 0, 1.0, "");
  EXPECT_EQ(s.state, CaseState::Done);
  EXPECT_EQ(s.meta["dt_crit"], 0.0005);
  s = judge_run(c, dir, 0, 11, 1.0, "");
  EXPECT_EQ(s.state, CaseState::Failed);
  EXPECT_NE(s.error.find("killed by signal 11"), std::string::npos);

  // Recorded, it is current only for the same scenario and while the log is there.
  write_case_status(dir, judge_run(c, dir, 0, 0, 1.0, ""));
  EXPECT_EQ(current_state(c, dir), CaseState::Done);
  SweepCase changed = c;
  changed.scenario_hash = "def";
  EXPECT_EQ(current_state(changed, dir), CaseState::Pending);
  fs::remove(dir / "forces.json");
  EXPECT_EQ(current_state(c, dir), CaseState::Pending);
}

}  // namespace
}  // namespace sweep_shard_results_test
}  // namespace organsim
