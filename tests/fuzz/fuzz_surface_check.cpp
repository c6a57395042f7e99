// Harness for the checks that guard CGAL Mesh_3 (meshing/surface_check.h),
// on small OFF surfaces the fuzzer mutates: fuzz::surface_check_input
// (tests/fuzz/fuzz_inputs.h). Mesh_3 itself is too slow to run per input.
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return organsim::fuzz::read_as_file(data, size, organsim::fuzz::surface_check_input);
}
