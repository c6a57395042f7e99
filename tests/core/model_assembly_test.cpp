// The linear-time assembly (core/model/tet_edges.h, layout_build.cpp) gives,
// array for array and bit for bit, what the straightforward algorithm gives:
// a global sort of all tet edges, a binary search per tet edge for its
// volume, and per-point lists sorted by the other end. Checked on a built
// model and after each of a sequence of random cuts.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/model/layout_build.h"
#include "core/model/stiffness.h"
#include "core/topology/blade.h"
#include "core/topology/topology_editor.h"
#include "tests/core/test_models.h"
#include "tests/core/topology_test_util.h"

namespace organsim {
namespace model_assembly_test {
namespace {

struct ReferenceSprings {
  std::vector<Edge> ends;
  std::vector<double> k;
};

ReferenceSprings reference_springs(const Model& m) {
  ReferenceSprings r;
  for (const Tet& t : m.tet_points)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) r.ends.push_back({std::min(t[i], t[j]), std::max(t[i], t[j])});
  std::sort(r.ends.begin(), r.ends.end());
  r.ends.erase(std::unique(r.ends.begin(), r.ends.end()), r.ends.end());
  std::vector<double> volume(r.ends.size(), 0.0);
  for (size_t t = 0; t < m.tet_points.size(); ++t) {
    const Tet& tet = m.tet_points[t];
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const Edge e{std::min(tet[i], tet[j]), std::max(tet[i], tet[j])};
        volume[std::lower_bound(r.ends.begin(), r.ends.end(), e) - r.ends.begin()] += m.tet_rest_volume[t];
      }
  }
  r.k = spring_stiffness(m.material, m.rest_position, r.ends, volume);
  return r;
}

GatherTable reference_table(const std::vector<std::vector<int32_t>>& items_of, int32_t chunk) {
  const int32_t n = static_cast<int32_t>(items_of.size()), nchunk = (n + chunk - 1) / chunk;
  GatherTable t;
  t.chunk_offset.push_back(0);
  for (int32_t c = 0; c < nchunk; ++c) {
    int32_t width = 0;
    for (int32_t p = c * chunk; p < std::min(n, (c + 1) * chunk); ++p) {
      t.count.push_back(static_cast<int32_t>(items_of[p].size()));
      width = std::max(width, t.count.back());
    }
    t.chunk_width.push_back(width);
    t.chunk_offset.push_back(t.chunk_offset.back() + width * chunk);
  }
  t.item.assign(t.chunk_offset.back(), -1);
  for (int32_t p = 0; p < n; ++p)
    for (size_t j = 0; j < items_of[p].size(); ++j)
      t.item[t.chunk_offset[p / chunk] + j * chunk + p % chunk] = items_of[p][j];
  return t;
}

void expect_table_eq(const GatherTable& a, const GatherTable& b, const char* what) {
  EXPECT_EQ(a.chunk_offset, b.chunk_offset) << what;
  EXPECT_EQ(a.chunk_width, b.chunk_width) << what;
  EXPECT_EQ(a.count, b.count) << what;
  EXPECT_EQ(a.item, b.item) << what;
}

// Every array of the assembled part of `m` against the straightforward algorithm.
void expect_reference_assembly(const Model& m) {
  const ReferenceSprings springs = reference_springs(m);
  ASSERT_EQ(m.spring_ends, springs.ends);
  EXPECT_EQ(m.spring_k, springs.k);  // bit for bit: the same sums in the same order
  const int32_t n = m.npoint(), chunk = m.layout.chunk_size;
  std::vector<std::vector<int32_t>> springs_of(n), tets_of(n);
  for (int32_t s = 0; s < m.nspring(); ++s) {
    springs_of[m.spring_ends[s][0]].push_back(s);
    springs_of[m.spring_ends[s][1]].push_back(s);
  }
  for (int32_t p = 0; p < n; ++p) {
    auto other = [&](int32_t s) { return m.spring_ends[s][0] + m.spring_ends[s][1] - p; };
    std::sort(springs_of[p].begin(), springs_of[p].end(), [&](int32_t a, int32_t b) { return other(a) < other(b); });
  }
  for (int32_t t = 0; t < m.ntet(); ++t)
    for (int32_t v : m.tet_points[t]) tets_of[v].push_back(t);
  const GatherTable ref_springs = reference_table(springs_of, chunk), ref_tets = reference_table(tets_of, chunk);
  expect_table_eq(m.layout.springs, ref_springs, "springs");
  expect_table_eq(m.layout.tets, ref_tets, "tets");
  for (size_t e = 0; e < ref_springs.item.size(); ++e) {
    const int32_t s = ref_springs.item[e];
    const int32_t p = point_of_entry(ref_springs, chunk, static_cast<int32_t>(e));
    ASSERT_EQ(m.layout.spring_other[e], s < 0 ? -1 : m.spring_ends[s][0] + m.spring_ends[s][1] - p) << "entry " << e;
  }
  static constexpr int kOthers[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (size_t e = 0; e < ref_tets.item.size(); ++e) {
    const int32_t t = ref_tets.item[e];
    std::array<int32_t, 3> expected{-1, -1, -1};
    if (t >= 0) {
      const int32_t p = point_of_entry(ref_tets, chunk, static_cast<int32_t>(e));
      const Tet& tet = m.tet_points[t];
      const int corner = static_cast<int>(std::find(tet.begin(), tet.end(), p) - tet.begin());
      for (int k = 0; k < 3; ++k) expected[k] = tet[kOthers[corner][k]];
    }
    ASSERT_EQ(m.layout.tet_others[e], expected) << "entry " << e;
  }
}

TEST(ModelAssembly, LinearTimeAssemblyEqualsTheStraightforwardOneAcrossRandomCuts) {
  Material material;
  material.density = 1000;
  material.young_modulus = 5000;
  material.volume_modulus = 2000;
  ModelOptions options;
  options.chunk_size = 8;  // several chunks on a small box
  options.sort_window = 16;
  Model current = build_model(testing::jittered_box(5, 1.0, 0.2, 17), material, options);
  expect_reference_assembly(current);
  TopologyEditor editor(current);
  std::mt19937 rng(31);
  int changes = 0;
  for (int i = 0; i < 300 && changes < 15; ++i) {
    const BladeSweep sweep = testing::random_short_blade(rng);
    Model next;
    ChangeCounts counts;
    const auto faces = faces_cut_by_blade(sweep, editor.faces(), current.tet_points, current.rest_position,
                                          editor.separated());
    if (!editor.separate(current, faces, next, counts)) continue;
    ++changes;
    SCOPED_TRACE("after cut " + std::to_string(changes));
    expect_reference_assembly(next);
    if (HasFatalFailure()) return;
    current = std::move(next);
  }
  EXPECT_EQ(changes, 15);
}

}  // namespace
}  // namespace model_assembly_test
}  // namespace organsim
