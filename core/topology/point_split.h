#pragma once
// Separate, don't delete: after faces are marked separated, every point on a
// newly separated face is split into one copy per group of its tets that
// still connect through unseparated faces (faces, not edges, so no hinge
// points survive). The group holding the point's lowest tet id keeps the id;
// the others get new ids appended in order (point id, then lowest tet id),
// so the result is deterministic. No tet is removed or subdivided.
#include <cstdint>
#include <vector>

#include "core/model/layout.h"
#include "core/topology/tet_faces.h"

namespace organsim {

struct PointSplit {
  std::vector<Tet> tet_points;           // every tet's vertices after the split (ntet x 4)
  std::vector<int32_t> appended_origin;  // for each new point, the point it copies
  int32_t points_split = 0;              // existing points that got at least one copy
};

// `tets` are the current tets (ids < npoint), `separated` (nface) already
// includes `new_faces`. Throws std::logic_error when two tets across an
// unseparated face do not share its vertices (a broken invariant).
PointSplit split_points(const std::vector<Tet>& tets, const TetFaces& faces, const std::vector<uint8_t>& separated,
                        const std::vector<int32_t>& new_faces, int32_t npoint);

// Edges (sorted ids) of the boundary surface of `tets` that belong to more
// than two boundary faces: where a split would leave the surface
// non-manifold (a component of a point wrapping around an opened edge).
// Boundary faces are found through `faces` (a face is open when the two tets
// across it no longer share its vertex ids), O(ntet).
std::vector<Edge> nonmanifold_boundary_edges(const std::vector<Tet>& tets, const TetFaces& faces);

// The same edges after `split` of `before` (the Model the split started
// from, whose boundary is manifold; `before` is its gather layout), found
// without visiting every tet: a
// face changes (opens, or its ids change) only if it holds a split point, so
// only edges of boundary faces of the split points' tets can have become
// non-manifold; each is counted over all tets around one of its ends,
// taken from `before`'s gather layout (copies: their origin's tets). Cost
// proportional to the split points' neighbourhood.
std::vector<Edge> nonmanifold_boundary_edges_near(const PointSplit& split, const GatherLayout& before,
                                                  const TetFaces& faces);

}  // namespace organsim
