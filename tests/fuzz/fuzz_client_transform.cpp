// Harness for the JSON matrix of `organsim serve --client-transform`:
// fuzz::client_transform_input (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  try {
    fuzz::client_transform_input(fuzz::as_text(data, size), fuzz::kSource);
  } catch (const Error& e) {
    fuzz::require_names_file(e, fuzz::kSource);
  }
  return 0;
}
