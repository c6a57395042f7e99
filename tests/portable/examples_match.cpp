// Built without -march=native (tests/CMakeLists.txt): writes the example
// surfaces as `organsim example` does and compares them byte for byte with
// the committed examples/, so their contents cannot depend on the
// instruction set the generator was compiled for.
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/mesh/example_shapes.h"
#include "core/mesh/mesh_io_detail.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: " << argv[0] << " EXAMPLES_DIR\n";
    return 2;
  }
  int mismatches = 0;
  for (const char* shape : {"liver", "sphere", "box"}) {
    std::ostringstream made;
    organsim::mesh_io::write_off(made, organsim::make_example_surface(shape));
    const std::string path = std::string(argv[1]) + "/" + shape + ".off";
    std::ifstream in(path, std::ios::binary);
    std::ostringstream committed;
    committed << in.rdbuf();
    if (made.str() != committed.str()) {
      std::cerr << path << ": differs from what the portable build generates\n";
      ++mismatches;
    } else {
      std::cout << path << ": identical\n";
    }
  }
  return mismatches == 0 ? 0 : 1;
}
