#pragma once
// Section parsers shared by the scenario's translation units (internal).
#include "core/scenario/json_reader.h"
#include "core/scenario/scenario.h"

namespace organsim::scenario_detail {

// `elastic`: every material gives E (none a spring_stiffness), which the
// sub-cell Hertz layer needs.
ToolDef parse_tool(const nlohmann::json& j, const JsonPath& at, bool elastic = true);
OutputsDef parse_outputs(const nlohmann::json& j, const JsonPath& at);
EventsDef parse_events(const nlohmann::json& j, const JsonPath& at);

}  // namespace organsim::scenario_detail
