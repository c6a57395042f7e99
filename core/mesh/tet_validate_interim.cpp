// INTERIM: a weak validate_tet_mesh so the readers link and are testable
// before the lead's core/mesh/tet_validate.cpp lands on main; the strong
// definition there wins. Delete this file once main has tet_validate.cpp.
#include <cmath>
#include <string>

#include "core/mesh/tet_mesh.h"
#include "core/util/error.h"

namespace organsim {

__attribute__((weak)) void validate_tet_mesh(const TetMesh& mesh, const std::string& source) {
  const auto n = static_cast<int64_t>(mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    if (!mesh.points[i].allFinite()) throw input_error(source, "point " + std::to_string(i) + " is not finite");
  }
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& tet = mesh.tets[t];
    for (int32_t v : tet) {
      if (v < 0 || v >= n) {
        throw input_error(source, "tet " + std::to_string(t) + " refers to point " + std::to_string(v) +
                                      ", expected an index in [0, " + std::to_string(n) + ")");
      }
    }
    const double volume = signed_volume(mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]], mesh.points[tet[3]]);
    if (volume == 0) throw input_error(source, "tet " + std::to_string(t) + " has zero volume");
    if (volume < 0) throw input_error(source, "tet " + std::to_string(t) + " is inverted (negative volume " + std::to_string(volume) + " m^3)");
  }
}

}  // namespace organsim
