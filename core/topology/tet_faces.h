#pragma once
// Face adjacency of a tet mesh, by tet id. Built once from the mesh as read:
// tet ids never change during a run (points are split, tets are not), so the
// adjacency stays valid after every topology change even though the two tets
// across a separated face no longer share vertex ids.
#include <array>
#include <cstdint>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

// Face i of a tet is the one opposite its vertex i.
struct TetFaces {
  std::vector<std::array<int32_t, 2>> tets;       // the two tets sharing each interior face (nface x 2)
  std::vector<std::array<int8_t, 2>> local;       // that face's index (0..3) in each of them (nface x 2)
  std::vector<std::array<int32_t, 4>> face_of_tet;  // interior face id of face i of tet t, -1 on the boundary (ntet x 4)

  int32_t nface() const { return static_cast<int32_t>(tets.size()); }
};

// Interior faces of `tets` in a deterministic order (sorted by vertex ids).
// Throws Error(Input) when a face is shared by more than two tets.
TetFaces build_tet_faces(const std::vector<Tet>& tets);

// The three vertices of face i of `tet`.
inline Tri tet_face(const Tet& tet, int i) {
  Tri f{};
  for (int k = 0, n = 0; k < 4; ++k)
    if (k != i) f[n++] = tet[k];
  return f;
}

}  // namespace organsim
