#include <cmath>
#include <string>

#include "core/mesh/tet_mesh.h"
#include "core/util/error.h"

namespace organsim {

void validate_tet_mesh(const TetMesh& mesh, const std::string& source) {
  if (mesh.points.empty()) throw input_error(source, "mesh has no points");
  if (mesh.tets.empty()) throw input_error(source, "mesh has no tetrahedra");
  if (!mesh.labels.empty() && mesh.labels.size() != mesh.tets.size()) {
    throw input_error(source, std::to_string(mesh.labels.size()) + " tet labels for " + std::to_string(mesh.tets.size()) +
                                  " tetrahedra, expected one per tetrahedron");
  }
  const auto npoint = static_cast<int64_t>(mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    if (!mesh.points[i].allFinite())
      throw input_error(source, "point " + std::to_string(i) + " has a non-finite coordinate");
  }
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& tet = mesh.tets[t];
    const std::string name = "tetrahedron " + std::to_string(t);
    for (int32_t v : tet) {
      if (v < 0 || v >= npoint)
        throw input_error(source, name + " has vertex index " + std::to_string(v) +
                                      ", expected 0.." + std::to_string(npoint - 1));
    }
    const Vec3 &a = mesh.points[tet[0]], &b = mesh.points[tet[1]], &c = mesh.points[tet[2]],
               &d = mesh.points[tet[3]];
    // Zero volume relative to the tet's own size, so the test is scale-free:
    // |V| <= 1e-9 L^3 means a dihedral angle or height around 1e-8 of the edges.
    double longest = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        longest = std::max(longest, (mesh.points[tet[i]] - mesh.points[tet[j]]).norm());
    const double volume = signed_volume(a, b, c, d);
    if (longest == 0 || std::abs(volume) <= 1e-9 * longest * longest * longest)
      throw input_error(source, name + " has zero volume (degenerate or coincident vertices)");
    if (volume < 0)
      throw input_error(source, name + " is inverted (negative volume " + std::to_string(volume) +
                                    " m^3); expected positive orientation");
  }
}

}  // namespace organsim
