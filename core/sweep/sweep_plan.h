#pragma once
// The files a sweep keeps at the top of its output folder:
//   OUTDIR/cases.json     the plan: every case's name, swept values and
//                         scenario hash (what --collect and shards agree on);
//   OUTDIR/manifest.json  the plan merged with every case's status.json.
// Each case runs in OUTDIR/cases/<name>/ from its scenario.json there.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/sweep/case_status.h"
#include "core/sweep/sweep_spec.h"

namespace organsim {

std::filesystem::path case_dir(const std::filesystem::path& outdir, const SweepCase& c);

// The case's swept values as {"field.path": value, ...}.
nlohmann::json overrides_json(const SweepCase& c);

nlohmann::json plan_json(const Sweep& sweep);
// The cases of a plan (names, overrides, hashes; no scenario text) from
// its text. Throws Error(Input) naming `source` and the entry when it is not
// a plan: an entry missing or of another type, a case name that is not a
// usable folder name (case_name_problem) or repeated.
Sweep parse_plan(const std::string& text, const std::string& source);
// OUTDIR/cases.json, parsed.
Sweep read_plan(const std::filesystem::path& outdir);

// Writes OUTDIR/cases.json unless it already holds this plan. With
// `must_match` (a shard, which shares the folder with other processes) a
// different plan there is an error instead of being replaced: the folder
// belongs to another sweep.
void write_plan(const std::filesystem::path& outdir, const Sweep& sweep, bool must_match);

struct ManifestCounts {
  int done = 0, failed = 0, pending = 0;
};

// What is known of one case: its state now and its status record (absent
// while pending).
struct CaseRecord {
  CaseState state = CaseState::Pending;
  std::optional<CaseStatus> status;
};

// The records of every case of the plan, from their folders.
std::vector<CaseRecord> read_case_records(const Sweep& plan, const std::filesystem::path& outdir);

// Every case of the plan with its state and status record, and the counts.
nlohmann::json manifest_json(const Sweep& plan, const std::vector<CaseRecord>& records,
                             ManifestCounts* counts = nullptr);
void write_manifest(const Sweep& plan, const std::vector<CaseRecord>& records, const std::filesystem::path& outdir,
                    ManifestCounts* counts = nullptr);

}  // namespace organsim
