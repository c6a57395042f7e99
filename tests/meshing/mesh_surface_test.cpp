// Meshing closed surfaces with CGAL Mesh_3: geometry of the result, the
// target point count, determinism and every bad-input error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <numbers>

#include "../core/mesh_io_test_util.h"
#include "core/mesh/example_shapes.h"
#include "core/mesh/mesh_io.h"
#include "meshing/mesh_surface.h"

namespace organsim {
namespace mesh_surface_test {
namespace {

using testing::error_message;
using testing::fresh_test_dir;
using testing::write_fixture;

MeshOptions cell_size(double h, bool exude = false) {
  MeshOptions o;
  o.cell_size = h;
  o.exude = exude;
  return o;
}

// Every edge of the boundary must be shared by exactly two boundary faces,
// once in each direction (closed and consistently oriented).
void expect_closed_boundary(const TetMesh& mesh) {
  std::map<std::pair<int32_t, int32_t>, int> directed;
  for (const Tri& f : boundary_triangles(mesh)) {
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  }
  size_t bad = 0;
  for (const auto& [edge, count] : directed) {
    if (count != 1 || directed.count({edge.second, edge.first}) != 1 || directed.at({edge.second, edge.first}) != 1) ++bad;
  }
  EXPECT_EQ(bad, 0u) << "boundary edges not shared by exactly two oppositely oriented faces";
}

TEST(MeshSurface, SphereIsClosedWithTheSphereVolume) {
  const double r = 0.05;
  MeshReport report;
  const TetMesh mesh = mesh_surface(make_sphere_surface(r, 4), cell_size(0.008, true), "sphere", &report);
  expect_closed_boundary(mesh);
  const double exact = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  // 2 %: the icosphere itself is 0.3 % small, Mesh_3's facet distance
  // (0.1 h = 0.8 mm, 1.6 % of r) bounds the rest.
  EXPECT_NEAR(tet_mesh_volume(mesh), exact, 0.02 * exact);
  EXPECT_GT(report.quality.min_tet_volume, 0.0);  // every tet positively oriented
  EXPECT_EQ(report.points, static_cast<int32_t>(mesh.points.size()));
  // docs/meshing.md promises a minimum dihedral angle of about 10 deg with
  // sliver removal (perturbation aims at 10 deg; this mesh gets 12.8 deg,
  // and meshing is deterministic, so the margin cannot drift by chance).
  EXPECT_GE(report.quality.min_dihedral_deg, 10.0);
  // The mesh's boundary is as large as the report says, and is outward.
  TriangleMesh boundary{mesh.points, boundary_triangles(mesh)};
  EXPECT_EQ(report.boundary_triangles, static_cast<int32_t>(boundary.faces.size()));
  EXPECT_NEAR(surface_volume(boundary), tet_mesh_volume(mesh), 1e-9 * exact);
}

TEST(MeshSurface, LiverTargetPointsLandWithinTenPercent) {
  // The paper's liver model has 7,750 points; meshing takes ~1 s here.
  const auto path = std::filesystem::path(ORGANSIM_SOURCE_DIR) / "examples" / "liver.off";
  MeshOptions options;
  options.target_points = 7750;
  options.exude = false;
  MeshReport report;
  const TetMesh mesh = mesh_surface_file(path, options, &report);
  EXPECT_NEAR(static_cast<double>(mesh.points.size()), 7750.0, 775.0);
  expect_closed_boundary(mesh);
  // Springs per point: the paper's Figure 2 peaks around 13-15; a mean far
  // from that would mean a different kind of mesh.
  const double mean = 2.0 * report.springs / report.points;
  EXPECT_GT(mean, 11.0);
  EXPECT_LT(mean, 16.0);
}

TEST(MeshSurface, LiverAtTheDefaultScenariosSizeKeepsTheDocumentedDihedralAngle) {
  // scenarios/default.json meshes examples/liver.off to 2,500 points with
  // sliver removal; docs/meshing.md promises about 10-11 deg (10.9 here).
  const auto path = std::filesystem::path(ORGANSIM_SOURCE_DIR) / "examples" / "liver.off";
  MeshOptions options;
  options.target_points = 2500;
  MeshReport report;
  mesh_surface_file(path, options, &report);
  EXPECT_GE(report.quality.min_dihedral_deg, 10.0);
  EXPECT_GT(report.quality.min_tet_volume, 0.0);
}

TEST(MeshSurface, SameInputGivesTheSameMesh) {
  const TriangleMesh sphere = make_sphere_surface(0.05, 3);
  const TetMesh a = mesh_surface(sphere, cell_size(0.012), "sphere");
  const TetMesh b = mesh_surface(make_liver_surface(2), cell_size(0.02), "liver");  // disturb any global state
  (void)b;
  const TetMesh c = mesh_surface(sphere, cell_size(0.012), "sphere");
  ASSERT_EQ(a.points.size(), c.points.size());
  ASSERT_EQ(a.tets.size(), c.tets.size());
  EXPECT_TRUE(a.points == c.points);
  EXPECT_TRUE(a.tets == c.tets);
}

TEST(MeshSurface, InwardSurfaceIsReversedAndNoted) {
  TriangleMesh inward = make_sphere_surface(0.05, 3);
  for (Tri& f : inward.faces) std::swap(f[1], f[2]);
  MeshReport report;
  const TetMesh mesh = mesh_surface(inward, cell_size(0.012), "inward.off", &report);
  EXPECT_GT(mesh.tets.size(), 0u);
  ASSERT_EQ(report.notes.size(), 1u);
  EXPECT_NE(report.notes[0].find("inward.off was oriented inward"), std::string::npos) << report.notes[0];
}

// Two spheres as one surface: overlapping (self-intersecting) or nested with
// the same orientation (no volume is bounded).
TriangleMesh two_spheres(double offset, double inner_scale) {
  TriangleMesh a = make_sphere_surface(0.05, 2);
  const TriangleMesh b = make_sphere_surface(0.05 * inner_scale, 2);
  const auto n = static_cast<int32_t>(a.points.size());
  for (const Vec3& p : b.points) a.points.push_back(p + Vec3(offset, 0, 0));
  for (const Tri& f : b.faces) a.faces.push_back({f[0] + n, f[1] + n, f[2] + n});
  return a;
}

TEST(MeshSurface, BadSurfacesAreErrorsNamingTheProblem) {
  const MeshOptions options = cell_size(0.01);
  const auto fails_with = [&](const TriangleMesh& surface, const std::string& expected) {
    const std::string msg = error_message([&] { mesh_surface(surface, options, "bad.off"); });
    EXPECT_EQ(msg.rfind("bad.off: ", 0), 0u) << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << msg;
  };
  fails_with(TriangleMesh{}, "no faces");

  TriangleMesh open = make_sphere_surface(0.05, 2);
  open.faces.pop_back();  // one triangle missing: its 3 edges are border edges
  fails_with(open, "open surface: 3 border edges");

  // Two spheres overlapping by half a radius: every crossing face pair counts.
  const std::string msg = error_message([&] { mesh_surface(two_spheres(0.075, 1.0), options, "bad.off"); });
  EXPECT_NE(msg.find("self-intersecting: "), std::string::npos) << msg;
  EXPECT_NE(msg.find(" pairs of faces intersect"), std::string::npos) << msg;

  fails_with(two_spheres(0.0, 0.5), "does not bound a volume");

  TriangleMesh flipped_one = make_sphere_surface(0.05, 2);
  std::swap(flipped_one.faces[0][1], flipped_one.faces[0][2]);
  fails_with(flipped_one, "not consistently oriented");

  TriangleMesh degenerate = make_sphere_surface(0.05, 1);
  degenerate.faces[3][1] = degenerate.faces[3][0];
  fails_with(degenerate, "face 3 repeats a vertex");
}

TEST(MeshSurface, AbsurdCellSizesAndFacetDistancesAreRefusedBeforeMeshing) {
  const TriangleMesh sphere = make_sphere_surface(0.05, 2);
  // 1e-5 m in a ball of 5 cm radius: ~5e11 points; Mesh_3 would run for days.
  MeshOptions tiny = cell_size(1e-5);
  std::string msg;
  try {
    mesh_surface(sphere, tiny, "ball.off");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    msg = e.what();
  }
  EXPECT_NE(msg.find("cell size 1e-05 m would make about "), std::string::npos) << msg;
  MeshOptions hairline = cell_size(0.01);
  hairline.facet_distance = 1e-9;
  msg.clear();
  try {
    mesh_surface(sphere, hairline, "ball.off");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    msg = e.what();
  }
  EXPECT_NE(msg.find("facet distance 1e-09 m is below 1e-06 of the surface's size"), std::string::npos) << msg;
}

TEST(MeshSurface, BadFilesAreErrorsNamingTheFile) {
  const auto dir = fresh_test_dir("meshing");
  const MeshOptions options = cell_size(0.01);
  const std::string missing = (dir / "missing.off").string();
  std::string msg = error_message([&] { mesh_surface_file(missing, options); });
  EXPECT_NE(msg.find(missing + ": no such file"), std::string::npos) << msg;

  const auto no_faces = write_fixture(dir / "nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n");
  msg = error_message([&] { mesh_surface_file(no_faces, options); });
  EXPECT_NE(msg.find("nofaces.off: no faces"), std::string::npos) << msg;

  const auto quad = write_fixture(dir / "quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  msg = error_message([&] { mesh_surface_file(quad, options); });
  EXPECT_NE(msg.find("quad.obj: line 5: face 0 has 4 vertices; not a triangle mesh"), std::string::npos) << msg;
}

// Real surfaces from Debian's libcgal-demo (CC0), unpacked into the test folder.
class CgalDataMeshes : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* archive = "/usr/share/doc/libcgal-dev/data.tar.gz";
    if (!std::filesystem::exists(archive)) GTEST_SKIP() << archive << " missing: install libcgal-demo";
    dir_ = fresh_test_dir("meshing");
    const std::string command = "tar xzf " + std::string(archive) + " -C " + dir_.string() +
                                " data/meshes/mushroom.off data/meshes/cow.off data/meshes/bull.off data/meshes/sphere.stl";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
  }
  std::filesystem::path dir_;
};

TEST_F(CgalDataMeshes, OpenSelfIntersectingAndBinaryStl) {
  const MeshOptions options = cell_size(0.1);
  // mushroom.off is open (a cap without its bottom).
  std::string msg = error_message([&] { mesh_surface_file(dir_ / "data/meshes/mushroom.off", options); });
  EXPECT_NE(msg.find("mushroom.off: open surface: "), std::string::npos) << msg;
  EXPECT_NE(msg.find(" border edges"), std::string::npos) << msg;
  // bull.off intersects itself.
  msg = error_message([&] { mesh_surface_file(dir_ / "data/meshes/bull.off", options); });
  EXPECT_NE(msg.find("bull.off: self-intersecting: 3 pairs of faces intersect"), std::string::npos) << msg;
  // cow.off also intersects itself, but first it has distinct vertices at
  // the same position, which the range checks name before CGAL runs.
  msg = error_message([&] { mesh_surface_file(dir_ / "data/meshes/cow.off", options); });
  EXPECT_NE(msg.find("cow.off: vertex 44 ("), std::string::npos) << msg;
  EXPECT_NE(msg.find("and vertex 2903 are at the same position"), std::string::npos) << msg;
  // sphere.stl: binary STL whose header starts with "FileType: Binary"; a
  // unit-diameter sphere that must weld closed and mesh.
  MeshReport report;
  const TetMesh mesh = mesh_surface_file(dir_ / "data/meshes/sphere.stl", cell_size(0.1), &report);
  expect_closed_boundary(mesh);
  EXPECT_GT(report.tets, 0);
}

}  // namespace
}  // namespace mesh_surface_test
}  // namespace organsim
