#pragma once
// Checks a surface before CGAL Mesh_3 sees it (Mesh_3 crashes on open input
// and silently makes bad models of self-intersecting input).
#include <string>
#include <vector>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// Throws Error(Input) "source: <problem>" when its numbers are out of range
// (check_surface_limits: non-finite, denormal, absurd size, duplicate
// vertices, zero-area faces, flat), when the surface has no faces, is
// not a triangle mesh, is not manifold or consistently oriented, is open
// (with the number of border edges), self-intersects (with the number of
// intersecting face pairs), does not bound a volume or encloses almost none. An inward-oriented
// surface is reversed and a note is appended. Returns the checked surface
// without unreferenced vertices.
TriangleMesh check_surface(const TriangleMesh& surface, const std::string& source, std::vector<std::string>& notes);

}  // namespace organsim
