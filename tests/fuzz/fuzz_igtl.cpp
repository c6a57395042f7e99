// Harness for the OpenIGTLink byte stream of `organsim serve`:
// fuzz::igtl_input (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  organsim::fuzz::igtl_input(organsim::fuzz::as_text(data, size));
  return 0;
}
