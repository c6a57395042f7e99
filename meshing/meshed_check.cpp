#include "meshing/meshed_check.h"

#include "core/util/error.h"

namespace organsim {

void check_meshed(const TetMesh& mesh, const std::string& source) {
  try {
    validate_tet_mesh(mesh, source);
  } catch (const Error& e) {
    throw Error(ErrorKind::Numerical, std::string("meshing gave a degenerate mesh, not used: ") + e.what() +
                                          "; try another cell size");
  }
}

}  // namespace organsim
