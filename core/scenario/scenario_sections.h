#pragma once
// Section parsers shared by the scenario's translation units (internal).
#include "core/scenario/json_reader.h"
#include "core/scenario/scenario.h"

namespace organsim::scenario_detail {

ToolDef parse_tool(const nlohmann::json& j, const JsonPath& at);
OutputsDef parse_outputs(const nlohmann::json& j, const JsonPath& at);
EventsDef parse_events(const nlohmann::json& j, const JsonPath& at);

}  // namespace organsim::scenario_detail
