#pragma once
// The scenario a live session replays as (OUTDIR/session.json): the served
// scenario with its file names made absolute, the tool's keyframes replaced
// by the session's path (LiveSession::keyframes), the duration by the time
// served, the client's cuts added to its events as scripted cuts over the
// ticks that applied them, the scenario's one-tick cuts that the session
// built off the tick's path given the applied_at they went in at, and the
// backend and precision that served it, so that `organsim
// run OUTDIR/session.json` steps the same ticks with the same tool centres
// and gives the same force log bit for bit.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/scenario/events.h"
#include "core/scenario/tool_spec.h"

namespace organsim {

nlohmann::json session_scenario(const std::filesystem::path& served_scenario, const std::vector<Keyframe>& keyframes,
                                double duration, const std::string& backend, const std::string& precision,
                                const std::vector<CutEvent>& client_cuts = {},
                                const std::vector<std::pair<size_t, double>>& scripted_applied = {});

}  // namespace organsim
