#pragma once
// Plain mesh containers handed between meshing/, core/ and the readers.
// Connectivity is kept apart from positions' meaning: indices are 0-based.
#include <string>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

// A closed triangle surface, as read from OFF/OBJ/STL/PLY.
struct TriangleMesh {
  std::vector<Vec3> points;  // vertex positions, m (npoint)
  std::vector<Tri> faces;    // vertex ids, counter-clockwise seen from outside (nface x 3)
};

// A tetrahedral volume mesh. Tets are positively oriented:
// dot(p1 - p0, cross(p2 - p0, p3 - p0)) > 0.
struct TetMesh {
  std::vector<Vec3> points;     // vertex positions, m (npoint)
  std::vector<Tet> tets;        // vertex ids (ntet x 4)
  // Each tet's subdomain label (a segmentation's label, a medit reference, a
  // Gmsh physical tag): empty for an unlabelled mesh, else one per tet.
  std::vector<int32_t> labels;
};

// Signed volume of the tet (a, b, c, d); positive for the orientation above.
inline double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

// Validates a tet mesh (indices in range, finite points, no unused-index
// gaps that matter, positive and non-tiny volumes); throws Error(Input)
// naming `source` and the first bad element. Implemented in tet_validate.cpp.
void validate_tet_mesh(const TetMesh& mesh, const std::string& source);

// A box [min, max] split into nx x ny x nz cubes of 6 positively oriented tets
// each (conforming, Kuhn subdivision). For tests and benchmarks without CGAL.
TetMesh make_box_tet_mesh(const Vec3& min, const Vec3& max, int nx, int ny, int nz);

}  // namespace organsim
