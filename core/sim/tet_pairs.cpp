#include "core/sim/tet_pairs.h"

#include <algorithm>

#include "core/sim/tet_batches.h"

namespace organsim {

namespace {

// True when `order` (four distinct positions 0..3) is an even permutation.
bool even(const std::array<int, 4>& order) {
  int inversions = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) inversions += order[i] > order[j];
  return inversions % 2 == 0;
}

// Position of point p in tet t's vertex order, -1 if it has none.
int position_in(const Tet& t, int32_t p) {
  for (int i = 0; i < 4; ++i)
    if (t[i] == p) return i;
  return -1;
}

}  // namespace

std::vector<TetPair> pair_model_tets(const Model& model) {
  const int32_t nt = model.ntet();
  const GatherTable& tets_of = model.layout.tets;  // each point's tets (layout.h)
  const int32_t C = model.layout.chunk_size;
  const std::vector<int32_t> order = tets_by_lowest_vertex(model);

  std::vector<char> taken(static_cast<size_t>(nt), 0);
  std::vector<TetPair> pairs;
  pairs.reserve(nt / 2 + 1);
  for (const int32_t t : order) {
    if (taken[t]) continue;
    taken[t] = 1;
    const Tet& v = model.tet_points[t];
    TetPair pair;
    pair.first = t;
    // The lone tet in the model's order: (a, b, c, d) = v, e = a.
    pair.v = {v[0], v[1], v[2], v[3], v[0]};
    for (int k = 3; k >= 0 && pair.second < 0; --k) {
      // The face opposite v[k]: (a, b, c, d) an even permutation of v with d = v[k].
      std::array<int, 4> pos{};
      for (int i = 0, j = 0; i < 4; ++i)
        if (i != k) pos[j++] = i;
      pos[3] = k;
      if (!even(pos)) std::swap(pos[0], pos[1]);
      const int32_t a = v[pos[0]], b = v[pos[1]], c = v[pos[2]], d = v[pos[3]];
      const int32_t first_slot = tets_of.chunk_offset[a / C] + a % C;
      for (int32_t j = 0; j < tets_of.count[a]; ++j) {
        const int32_t u = tets_of.item[first_slot + j * C];
        if (taken[u]) continue;
        const Tet& w = model.tet_points[u];
        const int pb = position_in(w, b), pc = position_in(w, c);
        if (pb < 0 || pc < 0) continue;
        const int pa = position_in(w, a), pe = 6 - pa - pb - pc;  // positions add up to 0 + 1 + 2 + 3
        if (!even({pa, pc, pb, pe})) continue;                    // (a, c, b, e) must keep w's orientation
        taken[u] = 1;
        pair.second = u;
        pair.v = {a, b, c, d, w[pe]};
        break;
      }
    }
    pairs.push_back(pair);  // its lowest vertex is t's: a tet with a lower one was taken before
  }
  return pairs;
}

}  // namespace organsim
