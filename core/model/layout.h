#pragma once
// Gather layout after the paper (points sorted by valence, springs and tets
// stored per point in slot-major order so empty slots are contiguous), in its
// modern form SELL-C-sigma: points are cut into chunks of C consecutive
// (internal) points; within a chunk, slot j of all C lanes is contiguous.
// Entry e of chunk c, slot j, lane l is at chunk_offset[c] + j * C + l.
// The valence sort happens only within windows of sigma points so that the
// locality order (reverse Cuthill-McKee) survives; sigma = npoint gives the
// paper's global sort (jagged diagonal storage).
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace organsim {

inline constexpr int32_t kDefaultChunkSize = 64;
inline constexpr int32_t kDefaultSortWindow = 256;

struct GatherTable {
  std::vector<int32_t> chunk_offset;  // first entry of each chunk (nchunk + 1)
  std::vector<int32_t> chunk_width;   // slots in each chunk = max count in it (nchunk)
  std::vector<int32_t> count;         // entries of each point (npoint)
  std::vector<int32_t> item;          // spring or tet id, -1 for padding (nentry)
};

// The point whose slot holds `entry` (padding entries included).
inline int32_t point_of_entry(const GatherTable& table, int32_t chunk_size, int32_t entry) {
  const auto next = std::upper_bound(table.chunk_offset.begin(), table.chunk_offset.end(), entry);
  const int32_t chunk = static_cast<int32_t>(next - table.chunk_offset.begin()) - 1;
  return chunk * chunk_size + (entry - table.chunk_offset[chunk]) % chunk_size;
}

struct GatherLayout {
  int32_t chunk_size = kDefaultChunkSize;  // C
  int32_t sort_window = kDefaultSortWindow;  // sigma
  int32_t nchunk = 0;
  // Springs per point; the other end of spring s seen from point p is
  // spring_ends[s][0] + spring_ends[s][1] - p.
  GatherTable springs;
  std::vector<int32_t> spring_other;  // other end, internal id, -1 for padding (nentry)
  // Tets per point: the other three vertices ordered so that (p, a, b, c) has
  // the tet's positive orientation ("the first point is inferred").
  GatherTable tets;
  std::vector<std::array<int32_t, 3>> tet_others;  // (nentry x 3), -1 for padding
};

}  // namespace organsim
