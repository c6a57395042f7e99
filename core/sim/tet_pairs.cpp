#include "core/sim/tet_pairs.h"

#include <algorithm>
#include <numeric>

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
  const int32_t nt = model.ntet(), np = model.npoint();
  // Tets of each point (CSR), to find a face's other tet.
  std::vector<int32_t> offset(static_cast<size_t>(np) + 1, 0), item(4 * static_cast<size_t>(nt));
  for (const Tet& t : model.tet_points)
    for (int32_t p : t) ++offset[p + 1];
  std::partial_sum(offset.begin(), offset.end(), offset.begin());
  std::vector<int32_t> fill(offset.begin(), offset.end() - 1);
  for (int32_t t = 0; t < nt; ++t)
    for (int32_t p : model.tet_points[t]) item[fill[p]++] = t;

  std::vector<int32_t> order(nt);
  std::iota(order.begin(), order.end(), 0);
  auto lowest = [&](int32_t t) { return *std::min_element(model.tet_points[t].begin(), model.tet_points[t].end()); };
  std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return lowest(a) < lowest(b); });

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
      for (int32_t i = offset[a]; i < offset[a + 1]; ++i) {
        const int32_t u = item[i];
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
