// Harness for the scenario JSON: fuzz::scenario_input, then for an accepted
// scenario fuzz::scenario_model (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  Scenario s;
  try {
    s = fuzz::scenario_input(fuzz::as_text(data, size), fuzz::kSource);
  } catch (const Error& e) {
    fuzz::require_names_file(e, fuzz::kSource);
    return 0;
  }
  try {
    fuzz::scenario_model(s);
  } catch (const Error&) {
    // Errors from here on name the JSON path or the mesh; cmd_run adds the file.
  }
  return 0;
}
