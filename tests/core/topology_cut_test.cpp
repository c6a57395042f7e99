// Cuts by face separation and point splitting (issue 8): the invariants,
// mass and momentum across every change, through and partial cuts.
#include <gtest/gtest.h>

#include <random>

#include "core/sim/reference_forces.h"
#include "core/topology/blade.h"
#include "core/topology/point_split.h"
#include "core/topology/topology_editor.h"
#include "tests/core/test_models.h"
#include "tests/core/topology_test_util.h"

namespace organsim {
namespace topology_cut_test {
namespace {

Material soft() {
  Material m;
  m.density = 1000;
  m.young_modulus = 5000;
  m.spring_damping_time = 1e-3;
  return m;
}

// A blade whose edge spans y in [-1, 2] (wider than the unit box) at height
// z, moving from z = z0 down to z = z1 in the plane x = x_cut.
BladeSweep vertical_sweep(double x_cut, double z0, double z1) {
  return {Vec3(x_cut, -1, z0), Vec3(x_cut, 2, z0), Vec3(x_cut, -1, z1), Vec3(x_cut, 2, z1)};
}

TEST(TetFaces, CountsInteriorFacesOfABox) {
  const TetMesh mesh = make_box_tet_mesh(Vec3::Zero(), Vec3::Ones(), 3, 3, 3);
  const TetFaces faces = build_tet_faces(mesh.tets);
  // 4 faces per tet; each boundary square is 2 triangles on 6 sides of 3x3 squares.
  const int boundary = 6 * 9 * 2;
  EXPECT_EQ(faces.nface(), (4 * static_cast<int>(mesh.tets.size()) - boundary) / 2);
  for (int32_t f = 0; f < faces.nface(); ++f) {
    Tri a = tet_face(mesh.tets[faces.tets[f][0]], faces.local[f][0]);
    Tri b = tet_face(mesh.tets[faces.tets[f][1]], faces.local[f][1]);
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    ASSERT_EQ(a, b) << "face " << f;
  }
}

TEST(SplitPoints, TwoTetsAcrossOneFaceBecomeSixPoints) {
  // Two tets sharing the face (0, 1, 2): separating it frees all three points.
  const std::vector<Tet> tets = {{0, 1, 2, 3}, {0, 2, 1, 4}};
  const TetFaces faces = build_tet_faces(tets);
  ASSERT_EQ(faces.nface(), 1);
  const std::vector<uint8_t> separated = {1};
  const PointSplit split = split_points(tets, faces, separated, {0}, 5);
  EXPECT_EQ(split.points_split, 3);
  EXPECT_EQ(split.appended_origin, (std::vector<int32_t>{0, 1, 2}));
  // Tet 0 (lowest id) keeps the ids; tet 1 gets the copies 5, 6, 7.
  EXPECT_EQ(split.tet_points[0], tets[0]);
  EXPECT_EQ(split.tet_points[1], (Tet{5, 7, 6, 4}));
}

TEST(Blade, SegmentTriangleCrossing) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(segment_crosses_triangle(Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), a, b, c));
  EXPECT_FALSE(segment_crosses_triangle(Vec3(0.2, 0.2, 0.1), Vec3(0.2, 0.2, 1), a, b, c));  // stops short
  EXPECT_FALSE(segment_crosses_triangle(Vec3(0.8, 0.8, -1), Vec3(0.8, 0.8, 1), a, b, c));   // beside it
  EXPECT_FALSE(segment_crosses_triangle(Vec3(-1, 0.2, 0), Vec3(2, 0.2, 0), a, b, c));       // in its plane
}

// Cuts `model` with `sweep`; returns false when nothing changed.
bool cut(TopologyEditor& editor, const Model& current, const BladeSweep& sweep, const std::vector<Vec3>& x,
         Model& next, ChangeCounts& counts) {
  const std::vector<int32_t> faces =
      faces_cut_by_blade(sweep, editor.faces(), current.tet_points, x, editor.separated());
  return editor.separate(current, faces, next, counts);
}

TEST(Cut, ThroughCutMakesTwoComponentsAndKeepsEverything) {
  const Model model = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Ones(), 4, 4, 4), soft(), {});
  TopologyEditor editor(model);
  Model next;
  ChangeCounts counts;
  // x = 0.5 is a grid plane: no tet straddles it, and the faces on it are
  // exactly those whose centroid segments the blade crosses.
  ASSERT_TRUE(cut(editor, model, vertical_sweep(0.5, 2, -1), model.rest_position, next, counts));
  EXPECT_EQ(testing::topology_problems(next), "");
  int32_t components = 0;
  const auto label = testing::point_components(next, &components);
  EXPECT_EQ(components, 2);
  // One component on each side: the label of every tet's points is that of its side.
  int32_t side_label[2] = {-1, -1};
  for (int32_t t = 0; t < next.ntet(); ++t) {
    Vec3 c = Vec3::Zero();
    for (int32_t p : next.tet_points[t]) c += 0.25 * next.rest_position[p];
    int32_t& want = side_label[c.x() < 0.5 ? 0 : 1];
    if (want < 0) want = label[next.tet_points[t][0]];
    for (int32_t p : next.tet_points[t]) ASSERT_EQ(label[p], want) << "tet " << t;
  }
  EXPECT_NE(side_label[0], side_label[1]);
  EXPECT_EQ(counts.faces_separated, 4 * 4 * 2);  // 4 x 4 squares of 2 triangles
  EXPECT_EQ(counts.points_split, 5 * 5);          // the grid points of the plane
  EXPECT_EQ(counts.points_added, 5 * 5);
  EXPECT_EQ(next.npoint(), model.npoint() + 25);
  // Total mass to 1e-12 relative: the copies' masses come from their own tets.
  EXPECT_NEAR(next.total_mass(), model.total_mass(), 1e-12 * model.total_mass());
  EXPECT_EQ(next.ntet(), model.ntet());
}

TEST(Cut, PartialCutLeavesOneComponentAndOpensOnlyBehindTheBlade) {
  const Model model = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Ones(), 4, 4, 4), soft(), {});
  TopologyEditor editor(model);
  Model next;
  ChangeCounts counts;
  // From above the box down to z = 0.5: the blade stops inside, on the grid
  // line z = 0.5 of the plane x = 0.5.
  ASSERT_TRUE(cut(editor, model, vertical_sweep(0.5, 2, 0.5), model.rest_position, next, counts));
  EXPECT_EQ(testing::topology_problems(next), "");
  int32_t components = 0;
  testing::point_components(next, &components);
  EXPECT_EQ(components, 1);
  EXPECT_EQ(counts.faces_separated, 4 * 2 * 2);  // 4 x 2 squares above z = 0.5
  // Points behind the blade (z = 0.75 and 1) split; those on its tip line
  // (z = 0.5) stay whole, joined through the faces below.
  EXPECT_EQ(counts.points_split, 5 * 2);
  for (int32_t p = model.npoint(); p < next.npoint(); ++p) EXPECT_GE(next.rest_position[p].z(), 0.75 - 1e-12);
}

TEST(Cut, HundredCutsConserveMassAndKeepInvariants) {
  Model current = build_model(testing::jittered_box(5, 1.0, 0.2, 11), soft(), {});
  const double mass0 = current.total_mass();
  TopologyEditor editor(current);
  std::mt19937 rng(5);
  int changes = 0;
  // 100 cuts that each change the Model (blades that only crack the inside
  // without splitting a point change nothing and are not counted).
  for (int i = 0; i < 1000 && changes < 100; ++i) {
    Model next;
    ChangeCounts counts;
    if (!cut(editor, current, testing::random_short_blade(rng), current.rest_position, next, counts)) continue;
    ++changes;
    ASSERT_EQ(testing::topology_problems(next), "") << "after cut " << i;
    // 1e-12 relative: sums of a few thousand positive terms in double.
    ASSERT_NEAR(next.total_mass(), mass0, 1e-12 * mass0) << "after cut " << i;
    current = std::move(next);
  }
  EXPECT_EQ(changes, 100);
}

TEST(Cut, MomentumAndForcesUnchangedAtTheCutInstant) {
  Material material = soft();
  material.volume_modulus = 2e4;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  const Model model = build_model(testing::jittered_box(4, 1.0, 0.2, 3), material, options);
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0, 1);
  std::vector<Vec3> x = model.rest_position, v(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] += 0.02 * Vec3(noise(rng), noise(rng), noise(rng));
    v[i] = Vec3(noise(rng), noise(rng), noise(rng));
  }
  TopologyEditor editor(model);
  Model next;
  ChangeCounts counts;
  ASSERT_TRUE(cut(editor, model, vertical_sweep(0.45, 2, -1), x, next, counts));
  // Copies carry their origin's position and velocity.
  std::vector<Vec3> x2 = x, v2 = v;
  for (int32_t p = model.npoint(); p < next.npoint(); ++p) {
    x2.push_back(x[next.origin[p]]);
    v2.push_back(v[next.origin[p]]);
  }
  Vec3 p0 = Vec3::Zero(), p1 = Vec3::Zero();
  for (int32_t i = 0; i < model.npoint(); ++i) p0 += model.mass[i] * v[i];
  for (int32_t i = 0; i < next.npoint(); ++i) p1 += next.mass[i] * v2[i];
  // 1e-12 relative: the masses are regrouped sums of the same terms.
  EXPECT_LT((p1 - p0).norm(), 1e-12 * model.total_mass() * 3);
  std::vector<Vec3> f0, f1;
  reference_internal_forces(model, x, v, f0);
  reference_internal_forces(next, x2, v2, f1);
  std::vector<Vec3> summed(model.npoint(), Vec3::Zero());
  for (int32_t i = 0; i < next.npoint(); ++i) summed[next.origin[i]] += f1[i];
  double scale = 0;
  for (const Vec3& f : f0) scale = std::max(scale, f.norm());
  // Each spring's stiffness is split between the sides in proportion to its
  // tets' volumes: the copies' forces sum to the original's to round-off.
  for (int32_t i = 0; i < model.npoint(); ++i) EXPECT_LT((summed[i] - f0[i]).norm(), 1e-9 * scale) << "point " << i;
}

}  // namespace
}  // namespace topology_cut_test
}  // namespace organsim

namespace organsim {
namespace topology_cut_test {
namespace {

// Seeded random blades chosen to hit degenerate cases on the unjittered
// grid: edges and sweeps through grid vertices, along grid edges, in the
// planes of faces, the same blade repeated, and blades through pieces
// already cut free (in the deformed configuration). Never a crash, the
// invariants after every change, mass to 1e-12.
TEST(Cut, SeededDegenerateBladesKeepTheInvariants) {
  Model current = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Ones(), 4, 4, 4), soft(), {});
  const double mass0 = current.total_mass();
  TopologyEditor editor(current);
  std::mt19937 rng(2024);
  std::uniform_int_distribution<int> grid(0, 4), kind(0, 4);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  auto node = [&]() -> Vec3 { return 0.25 * Vec3(grid(rng), grid(rng), grid(rng)); };
  std::vector<Vec3> x = current.rest_position;
  BladeSweep last{node(), node(), node(), node()};
  int changes = 0;
  for (int i = 0; i < 300; ++i) {
    BladeSweep sweep = last;
    switch (kind(rng)) {
      case 0:  // ends and sweep through grid vertices
        sweep = {node(), node(), node(), node()};
        break;
      case 1: {  // along a grid edge, moved along another
        const Vec3 a = node();
        const Vec3 e = 0.25 * Vec3::Unit(grid(rng) % 3), m = 0.5 * Vec3::Unit(grid(rng) % 3);
        sweep = {a, a + e, a + m, a + e + m};
        break;
      }
      case 2: {  // in the plane of grid faces (z = const)
        const double z = grid(rng) * 0.25;
        sweep = {Vec3(u(rng), u(rng), z), Vec3(u(rng), u(rng), z), Vec3(u(rng), u(rng), z), Vec3(u(rng), u(rng), z)};
        break;
      }
      case 3:  // the previous blade again
        sweep = last;
        break;
      default:  // anywhere, through whatever was cut free before
        sweep = {Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)),
                 Vec3(u(rng), u(rng), u(rng))};
    }
    last = sweep;
    Model next;
    ChangeCounts counts;
    if (!cut(editor, current, sweep, x, next, counts)) continue;
    ++changes;
    ASSERT_EQ(testing::topology_problems(next), "") << "after blade " << i;
    ASSERT_NEAR(next.total_mass(), mass0, 1e-12 * mass0) << "after blade " << i;
    // Deform: copies take their origin's position, and pieces drift apart a
    // little so later blades meet a cut-up, moved configuration.
    for (int32_t p = current.npoint(); p < next.npoint(); ++p) x.push_back(x[next.origin[p]]);
    int32_t ncomp = 0;
    const auto label = testing::point_components(next, &ncomp);
    for (int32_t p = 0; p < next.npoint(); ++p) x[p] += 0.01 * Vec3(label[p] % 3, (label[p] / 3) % 3, 0) / ncomp;
    current = std::move(next);
  }
  EXPECT_GT(changes, 20);
}

}  // namespace
}  // namespace topology_cut_test
}  // namespace organsim
