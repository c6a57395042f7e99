// Harness for the files `organsim sweep --collect` reads from a sweep's
// folder: fuzz::sweep_files_input (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return organsim::fuzz::read_as_file(data, size, organsim::fuzz::sweep_files_input);
}
