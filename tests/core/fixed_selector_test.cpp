// Fixed-point selectors on a box mesh whose points are known: each selector
// kind alone, and several together, fix exactly the expected points (a point
// is fixed when any selector matches it), in the user's input numbering even
// though the Model reorders points internally. A box, plane or sphere that
// matches no point, or selectors that hold every point, are scenario errors,
// not a model left free to fall or one that cannot move.
#include <gtest/gtest.h>

#include <set>

#include "core/mesh/tet_mesh.h"
#include "core/model/model.h"
#include "core/util/error.h"

namespace organsim {
namespace fixed_selector_test {
namespace {

// A 4 x 4 x 4 grid of 2.5 cm cubes: 125 points at multiples of 0.025 m.
TetMesh grid() { return make_box_tet_mesh({0, 0, 0}, {0.1, 0.1, 0.1}, 4, 4, 4); }

// Input ids of the points the Model fixed.
std::set<int32_t> fixed_inputs(const TetMesh& mesh, const std::vector<FixedSelector>& selectors) {
  ModelOptions options;
  options.fixed = selectors;
  const Model model = build_model(mesh, Material{}, options, "grid");
  std::set<int32_t> out;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if (model.fixed[i]) out.insert(model.input_of_internal[i]);
  }
  return out;
}

// Input ids of the points satisfying `match`, by brute force.
template <class F>
std::set<int32_t> points_where(const TetMesh& mesh, F&& match) {
  std::set<int32_t> out;
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    if (match(mesh.points[i])) out.insert(static_cast<int32_t>(i));
  }
  return out;
}

FixedSelector sphere(const Vec3& center, double radius) {
  FixedSelector s;
  s.kind = FixedSelector::Kind::Sphere;
  s.center = center;
  s.radius = radius;
  return s;
}

FixedSelector indices(std::vector<int32_t> ids) {
  FixedSelector s;
  s.kind = FixedSelector::Kind::Indices;
  s.indices = std::move(ids);
  return s;
}

FixedSelector plane(const Vec3& point, const Vec3& normal) {
  FixedSelector s;
  s.kind = FixedSelector::Kind::Plane;
  s.point = point;
  s.normal = normal;
  return s;
}

// What build_model says of these selectors on the grid.
std::string refusal(const std::vector<FixedSelector>& selectors) {
  ModelOptions options;
  options.fixed = selectors;
  try {
    build_model(grid(), Material{}, options, "grid");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Scenario);
    return e.what();
  }
  ADD_FAILURE() << "accepted";
  return "";
}

FixedSelector box(const Vec3& min, const Vec3& max) {
  FixedSelector s;
  s.kind = FixedSelector::Kind::Box;
  s.min = min;
  s.max = max;
  return s;
}

TEST(FixedSelectors, SphereFixesThePointsWithinItsRadius) {
  const TetMesh mesh = grid();
  // About the corner (0, 0, 0) with radius 0.03: the corner and its three
  // neighbours 0.025 m away; the face diagonals (0.035 m) stay free.
  const std::set<int32_t> got = fixed_inputs(mesh, {sphere({0, 0, 0}, 0.03)});
  EXPECT_EQ(got.size(), 4u);
  EXPECT_EQ(got, points_where(mesh, [](const Vec3& x) { return x.norm() <= 0.03; }));
}

TEST(FixedSelectors, IndicesAreTheUsersNumberingNotTheInternalOne) {
  const TetMesh mesh = grid();
  const std::set<int32_t> got = fixed_inputs(mesh, {indices({0, 7, 124, 62})});
  EXPECT_EQ(got, (std::set<int32_t>{0, 7, 62, 124}));
  // And the Model's own positions of those points are the input's.
  ModelOptions options;
  options.fixed = {indices({7})};
  const Model model = build_model(mesh, Material{}, options, "grid");
  EXPECT_EQ(model.rest_position[model.internal_of_input[7]], mesh.points[7]);
  EXPECT_TRUE(model.fixed[model.internal_of_input[7]]);
}

TEST(FixedSelectors, SeveralSelectorsFixTheirUnionExactly) {
  const TetMesh mesh = grid();
  const std::vector<FixedSelector> selectors = {
      box({-1, -1, -1}, {1, 1, 1e-9}),       // the bottom face, z = 0: 25 points
      sphere({0.1, 0.1, 0.1}, 0.03),         // the top corner and its 3 neighbours
      indices({0, 1, 62}),                   // 0 and 1 are on the bottom face already; 62 is inside
  };
  const std::set<int32_t> expected = points_where(mesh, [](const Vec3& x) {
    return x.z() <= 1e-9 || (x - Vec3(0.1, 0.1, 0.1)).norm() <= 0.03;
  });
  std::set<int32_t> with_62 = expected;
  with_62.insert(62);
  EXPECT_EQ(expected.size(), 29u);
  EXPECT_EQ(fixed_inputs(mesh, selectors), with_62);
  EXPECT_EQ(with_62.size(), 30u);  // 62 = (2, 2, 2) is the centre, in neither region
}

TEST(FixedSelectors, AnIndexBeyondTheMeshIsAScenarioErrorNamingIt) {
  const TetMesh mesh = grid();
  ModelOptions options;
  options.fixed = {box({0, 0, 0}, {0, 0, 0}), indices({3, 125})};
  try {
    build_model(mesh, Material{}, options, "grid");
    FAIL() << "index 125 of 125 points was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Scenario);
    EXPECT_NE(std::string(e.what()).find("fixed[1].indices[1]"), std::string::npos) << e.what();
  }
}

TEST(FixedSelectors, OneThatMatchesNoPointIsRefusedWithTheMeshsExtent) {
  // A plane below the grid facing down (a surface in millimetres read as
  // metres, say), after one that holds the bottom face.
  const std::string below = refusal({plane({0, 0, 0.01}, {0, 0, -1}), plane({0, 0, -0.03}, {0, 0, -1})});
  EXPECT_NE(below.find("fixed[1].plane: matches no point of the mesh, which spans x 0 .. 0.1, y 0 .. 0.1, z 0 .. 0.1 m"),
            std::string::npos)
      << below;
  EXPECT_NE(refusal({box({0.2, 0.2, 0.2}, {0.3, 0.3, 0.3})}).find("fixed[0].box: matches no point"), std::string::npos);
  // Inside the grid, between its points (0.0125 from the nearest ones).
  EXPECT_NE(refusal({sphere({0.0125, 0.0125, 0.0125}, 0.01)}).find("fixed[0].sphere: matches no point"),
            std::string::npos);
}

TEST(FixedSelectors, SelectorsThatHoldEveryPointAreRefused) {
  // The bottom face's plane with its normal turned up holds all but the bottom face.
  EXPECT_EQ(fixed_inputs(grid(), {plane({0, 0, 0.01}, {0, 0, 1})}).size(), 100u);
  EXPECT_NE(refusal({plane({0, 0, 0.01}, {0, 0, 1}), plane({0, 0, 0.01}, {0, 0, -1})})
                .find("fixed: the selectors hold all 125 points of the mesh, so nothing can move"),
            std::string::npos);
}

}  // namespace
}  // namespace fixed_selector_test
}  // namespace organsim
