// Harness for the CSV force curve of `organsim fit --measured`:
// fuzz::measured_curve_input (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return organsim::fuzz::read_as_file(data, size, organsim::fuzz::measured_curve_input);
}
