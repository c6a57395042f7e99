// Tet mesh readers: the same tets in .mesh, .vtk and .msh give the same
// counts; orientation fix-up; bad elements are errors naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "mesh_io_test_util.h"

namespace organsim {
namespace mesh_io_tet_test {
namespace {

using testing::error_message;
using testing::five_tet_cube;
using testing::fresh_test_dir;
using testing::write_bad_tet_mesh;
using testing::write_fixture;

// Gmsh 2.2 text of `mesh` with node tags 101.. (not 1-based on purpose), a
// stray geometry node, and a triangle element that the reader must skip.
std::string gmsh22(const TetMesh& mesh) {
  std::string s = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"liver\"\n$EndPhysicalNames\n";
  s += "$Nodes\n";
  s += std::to_string(mesh.points.size() + 1) + "\n";
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    const Vec3& p = mesh.points[i];
    s += std::to_string(101 + i) + " " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  }
  s += "999 5 5 5\n$EndNodes\n$Elements\n";
  s += std::to_string(mesh.tets.size() + 1) + "\n";
  s += "1 2 2 0 1 101 102 103\n";
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    s += std::to_string(t + 2) + " 4 2 1 1";
    for (int32_t v : mesh.tets[t]) s.append(" ").append(std::to_string(101 + v));
    s += "\n";
  }
  return s + "$EndElements\n";
}

// Gmsh 4.1 text of `mesh`, all nodes and tets in one entity block each.
std::string gmsh41(const TetMesh& mesh) {
  const std::string n = std::to_string(mesh.points.size());
  const std::string m = std::to_string(mesh.tets.size());
  std::string s = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n";
  s.append("$Nodes\n1 ").append(n).append(" 1 ").append(n).append("\n3 1 0 ").append(n).append("\n");
  for (size_t i = 0; i < mesh.points.size(); ++i) s += std::to_string(i + 1) + "\n";
  for (const Vec3& p : mesh.points) s += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  s.append("$EndNodes\n$Elements\n1 ").append(m).append(" 1 ").append(m).append("\n3 1 4 ").append(m).append("\n");
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    s += std::to_string(t + 1);
    for (int32_t v : mesh.tets[t]) s.append(" ").append(std::to_string(v + 1));
    s += "\n";
  }
  return s + "$EndElements\n";
}

void expect_cube(const TetMesh& mesh, const std::string& what) {
  const MeshReport r = describe_tet_mesh(mesh);
  EXPECT_EQ(r.points, 8) << what;
  EXPECT_EQ(r.tets, 5) << what;
  EXPECT_EQ(r.springs, 18) << what;            // 12 cube edges + 6 face diagonals
  EXPECT_EQ(r.boundary_triangles, 12) << what;  // 2 per cube face
  EXPECT_NEAR(tet_mesh_volume(mesh), 1.0, 1e-12) << what;
}

TEST(TetMeshStats, FiveTetCubeHasKnownAnglesAndValences) {
  const MeshReport r = describe_tet_mesh(five_tet_cube());
  // Corner tets: 90 deg at the axis edges, acos(1/sqrt 3) = 54.74 deg at the
  // others; the regular middle tet: acos(1/3) = 70.53 deg everywhere.
  EXPECT_NEAR(r.quality.min_dihedral_deg, std::acos(1 / std::sqrt(3.0)) * 180 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(r.quality.max_dihedral_deg, 90.0, 1e-9);
  EXPECT_NEAR(r.quality.min_tet_volume, 1.0 / 6.0, 1e-12);
  // Circumradius of a corner tet sqrt(3)/2 over its shortest edge 1.
  EXPECT_NEAR(r.quality.max_radius_edge_ratio, std::sqrt(3.0) / 2, 1e-12);
  // Even corners have 3 edges + 3 diagonals, odd corners 3 edges.
  ASSERT_EQ(r.valence_histogram.size(), 7u);
  EXPECT_EQ(r.valence_histogram[3], 4);
  EXPECT_EQ(r.valence_histogram[6], 4);
  // Boundary faces are outward: their surface volume is the cube's.
  TriangleMesh boundary{five_tet_cube().points, boundary_triangles(five_tet_cube())};
  EXPECT_NEAR(surface_volume(boundary), 1.0, 1e-12);
}

TEST(TetMeshIo, SameTetsInEveryFormatGiveTheSameCounts) {
  const auto dir = fresh_test_dir("mesh_io");
  const TetMesh cube = five_tet_cube();
  write_tet_mesh(dir / "cube.mesh", cube);
  write_tet_mesh(dir / "cube.vtk", cube);
  write_fixture(dir / "cube22.msh", gmsh22(cube));
  write_fixture(dir / "cube41.msh", gmsh41(cube));
  for (const char* name : {"cube.mesh", "cube.vtk", "cube22.msh", "cube41.msh"}) {
    const TetMesh m = read_tet_mesh(dir / name);
    expect_cube(m, name);
    ASSERT_EQ(m.tets.size(), cube.tets.size());
    for (size_t t = 0; t < cube.tets.size(); ++t) EXPECT_EQ(m.tets[t], cube.tets[t]) << name << " tet " << t;
  }
}

TEST(TetMeshIo, VtkBinaryAnd51Layouts) {
  const auto dir = fresh_test_dir("mesh_io");
  const TetMesh cube = five_tet_cube();
  // VTK 5.1 ASCII: OFFSETS / CONNECTIVITY.
  std::string s = "# vtk DataFile Version 5.1\ncube\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 8 float\n";
  for (const Vec3& p : cube.points) s += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  s += "CELLS 6 20\nOFFSETS vtktypeint64\n0 4 8 12 16 20\nCONNECTIVITY vtktypeint64\n";
  for (const Tet& t : cube.tets) s += std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + " " + std::to_string(t[3]) + "\n";
  s += "CELL_TYPES 5\n10\n10\n10\n10\n10\nCELL_DATA 5\n";
  expect_cube(read_tet_mesh(write_fixture(dir / "cube51.vtk", s)), "vtk 5.1");

  // Legacy BINARY: big-endian doubles and int32.
  const auto big = [](const void* data, size_t size) {
    std::string raw(static_cast<const char*>(data), size);
    std::reverse(raw.begin(), raw.end());
    return raw;
  };
  std::string b = "# vtk DataFile Version 3.0\ncube\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 8 double\n";
  for (const Vec3& p : cube.points) {
    for (int c = 0; c < 3; ++c) b += big(&p[c], 8);
  }
  b += "\nCELLS 5 25\n";
  for (const Tet& t : cube.tets) {
    const int32_t four = 4;
    b += big(&four, 4);
    for (int32_t v : t) b += big(&v, 4);
  }
  b += "\nCELL_TYPES 5\n";
  for (int i = 0; i < 5; ++i) {
    const int32_t ten = 10;
    b += big(&ten, 4);
  }
  b += "\n";
  expect_cube(read_tet_mesh(write_fixture(dir / "cubebin.vtk", b)), "vtk binary");
}

TEST(TetMeshIo, AllNegativeTetsAreFlippedConsistently) {
  const auto dir = fresh_test_dir("mesh_io");
  TetMesh flipped = five_tet_cube();
  for (Tet& t : flipped.tets) std::swap(t[0], t[1]);  // every tet negative, as some tools write them
  write_bad_tet_mesh(dir / "neg.vtk", flipped);
  const TetMesh m = read_tet_mesh(dir / "neg.vtk");
  expect_cube(m, "flipped");
  EXPECT_NEAR(describe_tet_mesh(m).quality.min_tet_volume, 1.0 / 6.0, 1e-12);  // all positive now
}

TEST(TetMeshIo, BadTetsAreErrorsNamingFileAndElement) {
  const auto dir = fresh_test_dir("mesh_io");
  // One inverted tet among positive ones: an error, not a silent flip.
  TetMesh mixed = five_tet_cube();
  std::swap(mixed.tets[2][0], mixed.tets[2][1]);
  write_bad_tet_mesh(dir / "mixed.mesh", mixed);
  std::string msg = error_message([&] { read_tet_mesh(dir / "mixed.mesh"); });
  EXPECT_NE(msg.find("mixed.mesh"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tetrahedron 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("invert"), std::string::npos) << msg;

  // A flat tet (all four corners in the plane z = 0).
  TetMesh flat = five_tet_cube();
  flat.tets[1] = {0, 1, 3, 2};
  write_bad_tet_mesh(dir / "flat.vtk", flat);
  msg = error_message([&] { read_tet_mesh(dir / "flat.vtk"); });
  EXPECT_NE(msg.find("flat.vtk"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tetrahedron 1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("volume"), std::string::npos) << msg;

  // Out-of-range index in medit (counts from 1): named with its line.
  const auto range = write_fixture(dir / "range.mesh",
                                   "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
                                   "Tetrahedra\n1\n1 2 3 5 0\nEnd\n");
  msg = error_message([&] { read_tet_mesh(range); });
  EXPECT_NE(msg.find("range.mesh"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 11"), std::string::npos) << msg;
  EXPECT_NE(msg.find("refers to vertex 5"), std::string::npos) << msg;

  // Out-of-range in VTK (0-based): caught by validation, naming the tet.
  const auto vtk_range = write_fixture(dir / "range.vtk",
                                       "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
                                       "0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 4\nCELL_TYPES 1\n10\n");
  msg = error_message([&] { read_tet_mesh(vtk_range); });
  EXPECT_NE(msg.find("range.vtk"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tetrahedron 0"), std::string::npos) << msg;

  // Gmsh node that does not exist.
  const auto msh = write_fixture(dir / "range.msh",
                                 "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                                 "$Elements\n1\n1 4 0 1 2 3 7\n$EndElements\n");
  msg = error_message([&] { read_tet_mesh(msh); });
  EXPECT_NE(msg.find("range.msh"), std::string::npos) << msg;
  EXPECT_NE(msg.find("node 7"), std::string::npos) << msg;

  const auto no_tets = write_fixture(dir / "empty.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n0\nEnd\n");
  msg = error_message([&] { read_tet_mesh(no_tets); });
  EXPECT_NE(msg.find("no tetrahedra"), std::string::npos) << msg;

  const auto unknown = write_fixture(dir / "cube.off", "OFF\n");
  msg = error_message([&] { read_tet_mesh(unknown); });
  EXPECT_NE(msg.find("unknown tet mesh extension '.off'"), std::string::npos) << msg;
}

TEST(TetMeshIo, AMeshWithANonPositiveTetIsNeverWritten) {
  const auto dir = fresh_test_dir("tet_io");
  for (const char* name : {"flat.mesh", "inverted.vtk"}) {
    TetMesh bad = five_tet_cube();
    if (std::string(name) == "flat.mesh") bad.points[6] = bad.points[5];  // tets using 5 and 6 collapse
    else std::swap(bad.tets[3][0], bad.tets[3][1]);
    try {
      write_tet_mesh(dir / name, bad);
      ADD_FAILURE() << name << " was written";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Numerical);
      EXPECT_NE(std::string(e.what()).find(name + std::string(": not written: tetrahedron ")), std::string::npos)
          << e.what();
    }
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

}  // namespace
}  // namespace mesh_io_tet_test
}  // namespace organsim
