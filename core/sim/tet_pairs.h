#pragma once
// How the simd kernel's nodal volume and shear element passes read the tets: two tets that
// share a face are one lane, so two volumes cost five points' positions
// instead of eight, and each point of the shared face sums one entry (the
// pair's two volumes) instead of two.
#include <array>
#include <cstdint>
#include <vector>

#include "core/model/model.h"

namespace organsim {

// Points (a, b, c, d, e): the tets (a, b, c, d) and (a, c, b, e), each an
// even permutation of the model's own vertex order, so that with n =
// (b - a) x (c - a) their 6 V are n . (d - a) and -n . (e - a) with the
// signs the model's order gives. A lone tet has second = -1 and e = a (its
// second volume is then exactly 0).
struct TetPair {
  std::array<int32_t, 5> v;
  int32_t first = -1, second = -1;  // model tets
};

// Every model tet in exactly one pair, in order of the pairs' lowest vertex
// (the batches' locality): each tet, in that order, takes the first of its
// face neighbours not yet taken whose order agrees (a mesh in one
// orientation always does), else stays alone.
std::vector<TetPair> pair_model_tets(const Model& model);

}  // namespace organsim
