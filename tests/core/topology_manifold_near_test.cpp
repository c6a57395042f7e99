// The manifold check of a split looks only around the split points
// (nonmanifold_boundary_edges_near); it must find exactly the edges the
// check over every tet finds, including the cases that do have non-manifold
// edges (blades on grid vertices, edges and face planes of an unjittered box).
#include <gtest/gtest.h>

#include <random>

#include "core/topology/blade.h"
#include "core/topology/point_split.h"
#include "core/topology/topology_editor.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace topology_manifold_near_test {
namespace {

TEST(ManifoldNear, FindsTheSameEdgesAsTheCheckOverEveryTet) {
  Material material;
  material.density = 1000;
  material.young_modulus = 5000;
  Model current = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Ones(), 4, 4, 4), material, {});
  TopologyEditor editor(current);
  std::mt19937 rng(77);
  std::uniform_int_distribution<int> grid(0, 4);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  auto node = [&]() -> Vec3 { return 0.25 * Vec3(grid(rng), grid(rng), grid(rng)); };
  int splits = 0, with_bad = 0;
  for (int i = 0; i < 1500; ++i) {
    BladeSweep sweep{node(), node(), node(), node()};  // through grid vertices
    if (i % 3 == 1) {  // in the plane of grid faces
      const double z = grid(rng) * 0.25;
      sweep = {Vec3(u(rng), u(rng), z), Vec3(u(rng), u(rng), z), Vec3(u(rng), u(rng), z), Vec3(u(rng), u(rng), z)};
    } else if (i % 3 == 2) {  // anywhere
      sweep = {Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)),
               Vec3(u(rng), u(rng), u(rng))};
    }
    const auto faces = faces_cut_by_blade(sweep, editor.faces(), current.tet_points, current.rest_position,
                                          editor.separated());
    if (faces.empty()) continue;
    // The split the editor's first attempt makes, on a copy of its state.
    std::vector<uint8_t> separated = editor.separated();
    for (int32_t f : faces) separated[f] = 1;
    const PointSplit split = split_points(current.tet_points, editor.faces(), separated, faces, current.npoint());
    if (!split.appended_origin.empty()) {
      ++splits;
      const auto everywhere = nonmanifold_boundary_edges(split.tet_points, editor.faces());
      ASSERT_EQ(nonmanifold_boundary_edges_near(split, current.layout, editor.faces()), everywhere)
          << "blade " << i;
      with_bad += !everywhere.empty();
    }
    Model next;
    ChangeCounts counts;
    if (editor.separate(current, faces, next, counts)) current = std::move(next);
  }
  EXPECT_GT(splits, 30);
  EXPECT_GT(with_bad, 3);  // the cases the check exists for did occur
}

}  // namespace
}  // namespace topology_manifold_near_test
}  // namespace organsim
