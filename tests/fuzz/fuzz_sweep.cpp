// Harness for the sweep file: parse, expand and build every case's scenario
// (what `organsim sweep` does before it runs anything). The base scenario is
// always gentle_push.json (a fuzzed "scenario" path could name /dev/zero),
// and inputs that expand to more than 256 cases are skipped to keep each
// execution short; the limit itself is tested in tests/core.
#include <nlohmann/json.hpp>

#include "core/sweep/case_names.h"
#include "core/sweep/sweep_spec.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

size_t list_length(const nlohmann::ordered_json& j) { return j.is_array() ? j.size() : 1; }

size_t case_count(const nlohmann::ordered_json& j) {
  size_t n = 1;
  if (j.contains("cases")) n *= list_length(j["cases"]);
  for (const char* section : {"grid", "zip"}) {
    if (!j.contains(section) || !j[section].is_object()) continue;
    for (const auto& item : j[section].items()) {
      n *= std::max<size_t>(1, list_length(item.value()));
      if (n > 256) return n;
      if (section[0] == 'z') break;  // zip: one axis
    }
  }
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  const std::string text(fuzz::as_text(data, size));
  nlohmann::ordered_json j;
  try {
    j = nlohmann::ordered_json::parse(text);
  } catch (const nlohmann::json::exception&) {
    try {
      parse_sweep_text(text, fuzz::kSource);
      fuzz::broken("invalid JSON accepted");
    } catch (const Error& e) {
      fuzz::require_names_file(e);
    }
    return 0;
  }
  if (j.is_object()) {
    j["scenario"] = ORGANSIM_SOURCE_DIR "/scenarios/stress/gentle_push.json";
    if (case_count(j) > 256) return 0;
  }
  try {
    const Sweep sweep = parse_sweep(j, fuzz::kSource);
    fuzz::require(!sweep.cases.empty(), "sweep accepted without cases");
    for (const SweepCase& c : sweep.cases) {
      fuzz::require(case_name_problem(c.name).empty(), "sweep accepted a bad case name: " + c.name);
      fuzz::require(!c.scenario_text.empty(), "sweep case without a scenario");
    }
  } catch (const Error& e) {
    fuzz::require_names_file(e);
  }
  return 0;
}
