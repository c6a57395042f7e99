#pragma once
// The last check on what Mesh_3 produced, before anyone uses it: a mesh we
// would refuse to read back (zero or negative volumes) is never handed on.
#include <string>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// validate_tet_mesh, its Error(Input) turned into Error(Numerical) "meshing
// gave a degenerate mesh, not used: ...; try another cell size".
void check_meshed(const TetMesh& mesh, const std::string& source);

}  // namespace organsim
