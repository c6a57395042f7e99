// Harness for the labelled-image readers: fuzz::label_image_input
// (tests/fuzz/fuzz_inputs.h); a refusal names the file it was written to.
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  std::filesystem::path path;
  try {
    fuzz::label_image_input(fuzz::as_text(data, size), fuzz::kSource, &path);
  } catch (const Error& e) {
    fuzz::require_names_file(e, path.string());
  }
  return 0;
}
