// Harness for one surface reader (.off .obj .stl .ply .vtk .vtp, by the
// row's extension): fuzz::surface_input (tests/fuzz/fuzz_inputs.h).
#include "tests/fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return organsim::fuzz::read_as_file(data, size, organsim::fuzz::surface_input);
}
