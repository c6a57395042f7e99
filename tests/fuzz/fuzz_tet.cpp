// Harness for one tet mesh reader (.mesh .vtk .vtu .msh, by the row's
// extension): fuzz::tet_input (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return organsim::fuzz::read_as_file(data, size, organsim::fuzz::tet_input);
}
