// The simd kernel's tet pairs (core/sim/tet_pairs.h): every tet once,
// the two tets of a pair sharing a face, each volume the pair's formula
// gives equal to 6 V in the model's own vertex order, and batches of pairs
// sharing no point.
#include "core/sim/tet_pairs.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "core/sim/tet_batches.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace tet_pairs_test {
namespace {

// 6 V of the tet (a, b, c, d) at the rest positions.
double det6(const Model& m, int32_t a, int32_t b, int32_t c, int32_t d) {
  const Vec3 x = m.rest_position[a];
  return (m.rest_position[b] - x).cross(m.rest_position[c] - x).dot(m.rest_position[d] - x);
}

std::array<int32_t, 4> sorted(std::array<int32_t, 4> v) {
  std::sort(v.begin(), v.end());
  return v;
}

Model jittered_model(int n, unsigned seed) {
  Material material;
  material.young_modulus = 3000;
  material.poisson_ratio = 0.45;
  return build_model(testing::jittered_box(n, 0.05, 0.3, seed), material, {});
}

TEST(TetPairs, EveryTetOnceTwoPerLaneSharingAFaceWithTheVolumesOfTheModelsOrder) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const Model m = jittered_model(5, seed);
    const std::vector<TetPair> pairs = pair_model_tets(m);
    std::vector<int> seen(m.ntet(), 0);
    int32_t paired = 0;
    for (const TetPair& p : pairs) {
      const auto [a, b, c, d, e] = p.v;
      ASSERT_GE(p.first, 0);
      ++seen[p.first];
      EXPECT_EQ(sorted({a, b, c, d}), sorted(m.tet_points[p.first]));
      // The pair's first volume is the model's 6 V of its tet, sign included
      // (rounding: the same products in another order).
      const Tet& t = m.tet_points[p.first];
      const double first = det6(m, t[0], t[1], t[2], t[3]);
      EXPECT_NEAR(det6(m, a, b, c, d), first, 1e-12 * std::abs(first));
      if (p.second < 0) {
        EXPECT_EQ(e, a) << "a lone tet's second volume must be exactly 0";
        continue;
      }
      ++paired;
      ++seen[p.second];
      EXPECT_EQ(sorted({a, c, b, e}), sorted(m.tet_points[p.second]));
      const Tet& u = m.tet_points[p.second];
      const double second = det6(m, u[0], u[1], u[2], u[3]);
      EXPECT_NEAR(det6(m, a, c, b, e), second, 1e-12 * std::abs(second));
    }
    for (int32_t t = 0; t < m.ntet(); ++t) EXPECT_EQ(seen[t], 1) << "tet " << t;
    // Pairs in order of their lowest vertex (the batches' locality).
    for (size_t i = 1; i < pairs.size(); ++i)
      EXPECT_LE(*std::min_element(pairs[i - 1].v.begin(), pairs[i - 1].v.end()),
                *std::min_element(pairs[i].v.begin(), pairs[i].v.end()));
    // What the pairs are for: two volumes from five points. The greedy
    // matching pairs most tets; a box's corner tets may stay alone.
    std::cout << "seed " << seed << ": " << 2 * paired << " of " << m.ntet() << " tets paired\n";
    EXPECT_GT(2.0 * paired / m.ntet(), 0.9);
  }
}

TEST(TetPairs, BatchesHoldEveryPairOnceAndNoTwoPairsOfABatchShareAPoint) {
  // The shear element's pass adds each lane's five forces without a
  // conflict check: two lanes of a batch on one point would lose a force.
  const Model m = jittered_model(6, 5);
  const std::vector<TetPair> pairs = pair_model_tets(m);
  for (const int32_t lanes : {8, 16}) {
    const TetBatches batches = batch_tet_pairs(pairs, m.npoint(), lanes, 2);
    ASSERT_EQ(batches.slice_begin.size(), 3u);
    EXPECT_EQ(batches.slice_begin.back() * static_cast<size_t>(lanes), batches.lane_tet.size());
    std::vector<int> seen(pairs.size(), 0);
    for (size_t b = 0; b * lanes < batches.lane_tet.size(); ++b) {
      std::vector<int32_t> points;
      for (int32_t l = 0; l < lanes; ++l) {
        const int32_t i = batches.lane_tet[b * lanes + l];
        if (i < 0) continue;
        ++seen[i];
        std::array<int32_t, 5> v = pairs[i].v;
        std::sort(v.begin(), v.end());
        points.insert(points.end(), v.begin(), std::unique(v.begin(), v.end()));  // a lone tet repeats a
      }
      std::sort(points.begin(), points.end());
      EXPECT_EQ(std::adjacent_find(points.begin(), points.end()), points.end()) << "batch " << b;
    }
    for (size_t i = 0; i < pairs.size(); ++i) EXPECT_EQ(seen[i], 1) << "pair " << i;
  }
}

}  // namespace
}  // namespace tet_pairs_test
}  // namespace organsim
