// Harness for the sweep file: fuzz::sweep_input (tests/fuzz/fuzz_inputs.h),
// skipping inputs that expand to more than 256 cases.
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  const std::string_view text = fuzz::as_text(data, size);
  if (fuzz::sweep_case_bound(text) > 256) return 0;
  try {
    fuzz::sweep_input(text, fuzz::kSource);
  } catch (const Error& e) {
    fuzz::require_names_file(e, fuzz::kSource);
  }
  return 0;
}
