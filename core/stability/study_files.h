#pragma once
// The files a sharded `organsim study` shares in its output folder
// (docs/stability.md, docs/cluster.md). The reference step writes
// study_plan.json (what was asked, the head of study.json: the stability
// report and the reference's convergence, and the configurations in order)
// and study_reference.json (the trajectory every configuration is compared
// with); each shard reads both and writes study_runs/<k>.json for each of
// its configurations k; `--collect` reads the plan and the runs. Numbers are
// written as JSON's shortest exact text, so what a shard reads back is what
// was computed, bit for bit, and the collected table equals a local run's.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/stability/study.h"

namespace organsim {

// One configuration's result, as study.json and study.csv report it.
struct StudyOutcome {
  std::string integrator = "verlet";  // time.integrator's name (integrator_name)
  std::string backend, precision, device;
  double dt = 0;
  int32_t substeps = 0;
  bool ran = false;        // false: the backend could not be created
  bool stable = false;
  std::string reason;      // why unstable or not run
  double simulated = 0;    // s
  double wall = 0;         // s, stepping loop
  double steps_per_second = 0;
  StudyErrors errors;
};

struct StudyConfiguration {
  std::string backend, precision;
  int32_t substeps = 0;
  std::string integrator = "verlet";  // time.integrator's name; a file without it means "verlet"
};

struct StudyPlan {
  nlohmann::json request;  // the command line's study arguments; a shard's must be the same
  nlohmann::json head;     // study.json without "runs"
  std::vector<StudyConfiguration> configurations;
  double dt_crit = 0;      // s, head.stability.dt_crit
};

nlohmann::json plan_json(const StudyPlan& plan);
// Each parse_* throws Error(Input) naming `source` and the entry at fault.
StudyPlan parse_study_plan(const nlohmann::json& j, const std::string& source);

nlohmann::json trajectory_json(const Trajectory& t);
Trajectory parse_trajectory(const nlohmann::json& j, const std::string& source);

// A configuration's outcome with the configuration it belongs to.
nlohmann::json outcome_record_json(const StudyOutcome& o);
StudyOutcome parse_outcome_record(const nlohmann::json& j, const std::string& source);

// The JSON of `text` read from `source`, or of the file `path`; Error(Input) naming it.
nlohmann::json parse_study_json(const std::string& text, const std::string& source);
nlohmann::json read_study_file(const std::string& path);

}  // namespace organsim
