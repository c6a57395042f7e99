#include "core/model/ordering.h"

#include <algorithm>
#include <queue>

namespace organsim {

namespace {

struct Adjacency {
  std::vector<int32_t> offset;     // (npoint + 1)
  std::vector<int32_t> neighbour;  // (2 nedge), each list sorted by id
};

Adjacency make_adjacency(int32_t npoint, const std::vector<Edge>& edges) {
  Adjacency adj;
  adj.offset.assign(npoint + 1, 0);
  for (const Edge& e : edges) {
    ++adj.offset[e[0] + 1];
    ++adj.offset[e[1] + 1];
  }
  for (int32_t i = 0; i < npoint; ++i) adj.offset[i + 1] += adj.offset[i];
  adj.neighbour.resize(adj.offset[npoint]);
  std::vector<int32_t> fill(adj.offset.begin(), adj.offset.end() - 1);
  for (const Edge& e : edges) {
    adj.neighbour[fill[e[0]]++] = e[1];
    adj.neighbour[fill[e[1]]++] = e[0];
  }
  for (int32_t i = 0; i < npoint; ++i)
    std::sort(adj.neighbour.begin() + adj.offset[i], adj.neighbour.begin() + adj.offset[i + 1]);
  return adj;
}

int32_t degree(const Adjacency& adj, int32_t v) { return adj.offset[v + 1] - adj.offset[v]; }

// Breadth-first levels from `root` within its component; returns the last
// level's node of smallest degree and the depth (eccentricity).
std::pair<int32_t, int32_t> farthest(const Adjacency& adj, int32_t root, std::vector<int32_t>& level) {
  std::fill(level.begin(), level.end(), -1);
  std::queue<int32_t> queue;
  queue.push(root);
  level[root] = 0;
  int32_t depth = 0, best = root;
  while (!queue.empty()) {
    const int32_t v = queue.front();
    queue.pop();
    if (level[v] > depth || (level[v] == depth && degree(adj, v) < degree(adj, best))) {
      depth = level[v];
      best = v;
    }
    for (int32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
      const int32_t w = adj.neighbour[k];
      if (level[w] < 0) {
        level[w] = level[v] + 1;
        queue.push(w);
      }
    }
  }
  return {best, depth};
}

}  // namespace

std::vector<int32_t> reverse_cuthill_mckee(int32_t npoint, const std::vector<Edge>& edges) {
  const Adjacency adj = make_adjacency(npoint, edges);
  std::vector<int32_t> order;
  order.reserve(npoint);
  std::vector<uint8_t> placed(npoint, 0);
  std::vector<int32_t> level(npoint, -1), scratch;
  for (int32_t seed = 0; seed < npoint; ++seed) {
    if (placed[seed]) continue;
    // Pseudo-peripheral start (George-Liu): hop to the farthest node while
    // the eccentricity grows.
    int32_t root = seed;
    auto [far, depth] = farthest(adj, root, level);
    for (int iteration = 0; iteration < 8; ++iteration) {
      auto [next, next_depth] = farthest(adj, far, level);
      if (next_depth <= depth) break;
      root = far;
      far = next;
      depth = next_depth;
    }
    root = far;
    // Cuthill-McKee: breadth-first, neighbours by increasing degree.
    const size_t first = order.size();
    order.push_back(root);
    placed[root] = 1;
    for (size_t head = first; head < order.size(); ++head) {
      const int32_t v = order[head];
      scratch.clear();
      for (int32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k)
        if (!placed[adj.neighbour[k]]) scratch.push_back(adj.neighbour[k]);
      std::stable_sort(scratch.begin(), scratch.end(),
                       [&](int32_t a, int32_t b) { return degree(adj, a) < degree(adj, b); });
      for (int32_t w : scratch) {
        placed[w] = 1;
        order.push_back(w);
      }
    }
    std::reverse(order.begin() + static_cast<std::ptrdiff_t>(first), order.end());
  }
  return order;
}

void sort_by_valence_in_windows(std::vector<int32_t>& order, const std::vector<int32_t>& valence,
                                int32_t window) {
  const size_t w = window > 0 ? static_cast<size_t>(window) : order.size();
  for (size_t begin = 0; begin < order.size(); begin += w) {
    const auto first = order.begin() + static_cast<std::ptrdiff_t>(begin);
    const auto last = order.begin() + static_cast<std::ptrdiff_t>(std::min(order.size(), begin + w));
    std::stable_sort(first, last, [&](int32_t a, int32_t b) { return valence[a] > valence[b]; });
  }
}

}  // namespace organsim
