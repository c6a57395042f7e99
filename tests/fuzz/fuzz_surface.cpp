// Harness for one surface reader (.off .obj .stl .ply, by the row's
// extension): read, and when the read succeeds, write the surface as OFF and
// read it back unchanged (the writers print the shortest exact text).
#include <sstream>

#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_io_detail.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  TriangleMesh mesh;
  try {
    mesh = parse_surface(fuzz::as_text(data, size), fuzz::kSource);
  } catch (const Error& e) {
    fuzz::require_names_file(e);
    return 0;
  }
  fuzz::require_valid_surface(mesh);
  std::ostringstream off;
  mesh_io::write_off(off, mesh);
  const TriangleMesh again = parse_surface(off.str(), "again.off");
  fuzz::require(again.points == mesh.points && again.faces == mesh.faces, "OFF round trip changed the surface");
  return 0;
}
