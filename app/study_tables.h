#pragma once
// study.json, study.csv and study.png of `organsim study`, from the head of
// study.json (the scenario, the stability report, the reference) and each
// configuration's outcome: one writer for a local study and for the
// collected shards of one (`--collect`), so the two give the same files.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/stability/study_files.h"

namespace organsim::app {

// Writes the three files into `outdir` (created) and prints the table.
void write_study_outputs(const std::filesystem::path& outdir, const nlohmann::json& head, double dt_crit,
                         const std::vector<StudyOutcome>& runs);

}  // namespace organsim::app
