#pragma once
// Boundary surface of a tet mesh: the triangles owned by exactly one tet,
// oriented so their normals point out of the volume. Pure topology (no GL):
// the renderer draws these, and recomputes them whenever the topology changes.
#include <vector>

#include "core/util/vec.h"

namespace organsim {

// Faces of `tets` that belong to exactly one tet, counter-clockwise seen from
// outside, given positively oriented tets (dot(p1-p0, (p2-p0)x(p3-p0)) > 0).
// Vertex ids are those of `tets`. Deterministic order (sorted by vertex ids).
// `owner`, when given, receives each face's tet index (the frames colour a
// face by its tet's label).
std::vector<Tri> extract_boundary_faces(const std::vector<Tet>& tets, std::vector<int32_t>* owner = nullptr);

// Edges of a triangle surface whose faces are not all in one group (group[f]
// per face, e.g. the owning tet's label): where two labels meet on the
// surface. Sorted, each once.
std::vector<Edge> edges_between_face_groups(const std::vector<Tri>& faces, const std::vector<int32_t>& group);

// Volume enclosed by a closed, outward oriented triangle surface (divergence
// theorem: sum over faces of a . (b x c) / 6), m^3.
double enclosed_volume(const std::vector<Vec3>& points, const std::vector<Tri>& faces);

// Facts about a triangle surface used to check that it is a closed 2-manifold.
struct SurfaceTopology {
  int64_t vertices = 0;      // vertices referenced by at least one face
  int64_t edges = 0;         // unique undirected edges
  int64_t faces = 0;
  int64_t border_edges = 0;  // edges with one face
  int64_t nonmanifold_edges = 0;  // edges with more than two faces
  int64_t misoriented_edges = 0;  // two-face edges traversed the same way by both
  int64_t euler_characteristic() const { return vertices - edges + faces; }
  bool closed_and_oriented() const {
    return border_edges == 0 && nonmanifold_edges == 0 && misoriented_edges == 0;
  }
};
SurfaceTopology surface_topology(const std::vector<Tri>& faces);

// Area-weighted vertex normals (unit length; zero for unreferenced vertices).
void vertex_normals(const std::vector<Vec3>& points, const std::vector<Tri>& faces,
                    std::vector<Vec3>& normals);

}  // namespace organsim
