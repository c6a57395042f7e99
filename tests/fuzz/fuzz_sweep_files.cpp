// Harness for the files `organsim sweep --collect` reads from a sweep's
// folder: fuzz::sweep_files_input (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  try {
    fuzz::sweep_files_input(fuzz::as_text(data, size), fuzz::kSource);
  } catch (const Error& e) {
    fuzz::require_names_file(e, fuzz::kSource);
  }
  return 0;
}
