// Harness for the JSON matrix of `organsim serve --client-transform`:
// fuzz::client_transform_input (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return organsim::fuzz::read_as_file(data, size, organsim::fuzz::client_transform_input);
}
