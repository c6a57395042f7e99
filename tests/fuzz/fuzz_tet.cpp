// Harness for one tet mesh reader (.mesh .vtk .msh, by the row's extension):
// read and validate, and when that succeeds, write medit and VTK and read both
// back unchanged.
#include <sstream>

#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_io_detail.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

void require_round_trip(const organsim::TetMesh& mesh, const char* name,
                        void (*write)(std::ostream&, const organsim::TetMesh&)) {
  std::ostringstream out;
  write(out, mesh);
  const organsim::TetMesh again = organsim::parse_tet_mesh(out.str(), name);
  organsim::fuzz::require(again.points == mesh.points && again.tets == mesh.tets,
                          std::string("round trip through ") + name + " changed the mesh");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  TetMesh mesh;
  try {
    mesh = parse_tet_mesh(fuzz::as_text(data, size), fuzz::kSource);
  } catch (const Error& e) {
    fuzz::require_names_file(e);
    return 0;
  }
  fuzz::require_valid_tet_mesh(mesh);
  require_round_trip(mesh, "again.mesh", mesh_io::write_medit);
  require_round_trip(mesh, "again.vtk", mesh_io::write_vtk);
  return 0;
}
