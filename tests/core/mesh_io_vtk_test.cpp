// VTK surfaces and tet meshes (legacy polydata, XML .vtp and .vtu) and Gmsh
// 1.0: files written by VTK itself are read back exactly, files we write are
// opened by VTK with the same counts and values, bad files are clear errors.
#include <gtest/gtest.h>

#include <sstream>

#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "core/mesh/vtk_xml.h"
#include "mesh_io_test_util.h"
#include "vtk_client.h"

namespace organsim {
namespace mesh_io_vtk_test {
namespace {

using testing::error_message;
using testing::five_tet_cube;
using testing::fresh_test_dir;
using testing::octahedron;
using testing::run_vtk_python;
using testing::write_fixture;

// Python lines that build `vtk_points` and the cells of `mesh`.
std::string python_points(const std::vector<Vec3>& points) {
  std::ostringstream s;
  s.precision(17);
  s << "pts = vtk.vtkPoints()\npts.SetDataTypeToDouble()\n";
  for (const Vec3& p : points) s << "pts.InsertNextPoint(" << p.x() << ", " << p.y() << ", " << p.z() << ")\n";
  return s.str();
}

// Binary and XML files hold the doubles exactly; VTK's legacy ASCII writer
// prints fewer digits than round-trip needs, so those agree to 1e-9 m.
void expect_same_points(const std::vector<Vec3>& got, const std::vector<Vec3>& want, const std::string& what) {
  const double tolerance = what.find("legacy_ascii") != std::string::npos ? 1e-9 : 0.0;
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_LE((got[i] - want[i]).lpNorm<Eigen::Infinity>(), tolerance) << what << " point " << i;
  }
}

void expect_same_surface(const TriangleMesh& got, const TriangleMesh& want, const std::string& what) {
  ASSERT_EQ(got.points.size(), want.points.size()) << what;
  ASSERT_EQ(got.faces.size(), want.faces.size()) << what;
  expect_same_points(got.points, want.points, what);
  for (size_t f = 0; f < want.faces.size(); ++f) EXPECT_EQ(got.faces[f], want.faces[f]) << what << " face " << f;
}

void expect_same_tets(const TetMesh& got, const TetMesh& want, const std::string& what) {
  ASSERT_EQ(got.points.size(), want.points.size()) << what;
  ASSERT_EQ(got.tets.size(), want.tets.size()) << what;
  expect_same_points(got.points, want.points, what);
  for (size_t t = 0; t < want.tets.size(); ++t) EXPECT_EQ(got.tets[t], want.tets[t]) << what << " tet " << t;
}

TEST(VtkIo, ReadsTheSurfacesVtkWrites) {
  const auto dir = fresh_test_dir("mesh_io_vtk");
  TriangleMesh octa = octahedron();
  for (Vec3& p : octa.points) p = p * 0.1 + Vec3(0.01, -0.02, 0.3);  // not exact in float: Float64 kept
  std::string script = python_points(octa.points) + "polys = vtk.vtkCellArray()\n";
  for (const Tri& f : octa.faces) script += "polys.InsertNextCell(3, [" + std::to_string(f[0]) + ", " + std::to_string(f[1]) + ", " + std::to_string(f[2]) + "])\n";
  script += R"(pd = vtk.vtkPolyData()
pd.SetPoints(pts)
pd.SetPolys(polys)
def xml(name, mode, encode=True, order='little'):
    w = vtk.vtkXMLPolyDataWriter()
    w.SetFileName(name); w.SetInputData(pd); w.SetCompressorTypeToNone()
    getattr(w, 'SetDataModeTo' + mode)(); w.SetEncodeAppendedData(encode)
    if order == 'big': w.SetByteOrderToBigEndian()
    assert w.Write() == 1
xml('ascii.vtp', 'Ascii'); xml('binary.vtp', 'Binary'); xml('raw.vtp', 'Appended', False)
xml('big.vtp', 'Binary', True, 'big'); xml('base64.vtp', 'Appended', True)
z = vtk.vtkXMLPolyDataWriter(); z.SetFileName('zlib.vtp'); z.SetInputData(pd); z.SetDataModeToBinary(); z.Write()
for name, binary in (('legacy_ascii.vtk', False), ('legacy_binary.vtk', True)):
    w = vtk.vtkPolyDataWriter(); w.SetFileName(name); w.SetInputData(pd)
    if binary: w.SetFileTypeToBinary()
    w.Write()
quad = vtk.vtkPolyData(); quad.SetPoints(pts); q = vtk.vtkCellArray(); q.InsertNextCell(4, [0, 2, 1, 3]); quad.SetPolys(q)
w = vtk.vtkPolyDataWriter(); w.SetFileName('quad.vtk'); w.SetInputData(quad); w.Write()
)";
  run_vtk_python(script, dir);
  for (const char* name : {"ascii.vtp", "binary.vtp", "raw.vtp", "big.vtp", "legacy_ascii.vtk", "legacy_binary.vtk"}) {
    ASSERT_TRUE(is_surface_path(dir / name)) << name;
    expect_same_surface(read_surface(dir / name), octa, name);
  }
  std::string msg = error_message([&] { read_surface(dir / "zlib.vtp"); });
  EXPECT_NE(msg.find("zlib.vtp"), std::string::npos) << msg;
  EXPECT_NE(msg.find("compressed"), std::string::npos) << msg;
  msg = error_message([&] { read_surface(dir / "base64.vtp"); });
  EXPECT_NE(msg.find("appended data encoded \"base64\""), std::string::npos) << msg;
  msg = error_message([&] { read_surface(dir / "quad.vtk"); });
  EXPECT_NE(msg.find("quad.vtk"), std::string::npos) << msg;
  EXPECT_NE(msg.find("polygon 0 has 4 points"), std::string::npos) << msg;
}

TEST(VtkIo, ReadsTheTetMeshesVtkWrites) {
  const auto dir = fresh_test_dir("mesh_io_vtk");
  TetMesh cube = five_tet_cube();
  for (Vec3& p : cube.points) p = p * 0.05 + Vec3(0.1, 0.2, -0.3);
  std::string script = python_points(cube.points) + "ug = vtk.vtkUnstructuredGrid()\nug.SetPoints(pts)\n";
  for (const Tet& t : cube.tets) {
    script += "ug.InsertNextCell(vtk.VTK_TETRA, 4, [" + std::to_string(t[0]) + ", " + std::to_string(t[1]) + ", " +
              std::to_string(t[2]) + ", " + std::to_string(t[3]) + "])\n";
  }
  script += R"(ug.InsertNextCell(vtk.VTK_TRIANGLE, 3, [0, 1, 2])
def xml(name, mode, encode=True, header64=False):
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(name); w.SetInputData(ug); w.SetCompressorTypeToNone()
    getattr(w, 'SetDataModeTo' + mode)(); w.SetEncodeAppendedData(encode)
    if header64: w.SetHeaderTypeToUInt64()
    assert w.Write() == 1
xml('ascii.vtu', 'Ascii'); xml('binary.vtu', 'Binary'); xml('raw.vtu', 'Appended', False)
xml('binary64.vtu', 'Binary', True, True); xml('xml_named.vtk', 'Binary')
for name, binary in (('legacy_ascii.vtk', False), ('legacy_binary.vtk', True)):
    w = vtk.vtkUnstructuredGridWriter(); w.SetFileName(name); w.SetInputData(ug)
    if binary: w.SetFileTypeToBinary()
    w.Write()
)";
  run_vtk_python(script, dir);
  for (const char* name : {"ascii.vtu", "binary.vtu", "raw.vtu", "binary64.vtu", "xml_named.vtk", "legacy_ascii.vtk",
                           "legacy_binary.vtk"}) {
    ASSERT_TRUE(is_tet_mesh_path(dir / name)) << name;
    expect_same_tets(read_tet_mesh(dir / name), cube, name);  // the triangle cell is read past
  }
}

TEST(VtkIo, VtkOpensWhatWeWriteWithTheSameValues) {
  const auto dir = fresh_test_dir("mesh_io_vtk");
  TetMesh cube = five_tet_cube();
  for (Vec3& p : cube.points) p = p * 0.03 + Vec3(0.1, 0.2, 0.3);
  write_tet_mesh(dir / "cube.vtu", cube);
  TriangleMesh octa = octahedron();
  for (Vec3& p : octa.points) p *= 0.07;
  write_surface(dir / "octa.vtp", octa);
  write_surface(dir / "octa.vtk", octa);
  const std::string out = run_vtk_python(R"(
def dump(g):
    print(g.GetNumberOfPoints(), g.GetNumberOfCells())
    for i in range(g.GetNumberOfPoints()): print(*[repr(c) for c in g.GetPoint(i)])
    for c in range(g.GetNumberOfCells()):
        cell = g.GetCell(c)
        print(g.GetCellType(c), *[cell.GetPointId(k) for k in range(cell.GetNumberOfPoints())])
for name, reader in (('cube.vtu', vtk.vtkXMLUnstructuredGridReader()), ('octa.vtp', vtk.vtkXMLPolyDataReader()),
                     ('octa.vtk', vtk.vtkPolyDataReader())):
    reader.SetFileName(name); reader.Update(); dump(reader.GetOutput())
)", dir);
  std::istringstream in(out);
  const auto check = [&](const std::vector<Vec3>& points, const auto& cells, int type, const char* what) {
    size_t npoint = 0, ncell = 0;
    in >> npoint >> ncell;
    ASSERT_EQ(npoint, points.size()) << what;
    ASSERT_EQ(ncell, cells.size()) << what;
    for (const Vec3& p : points) {
      Vec3 q;
      in >> q.x() >> q.y() >> q.z();
      EXPECT_EQ(q, p) << what;  // Float64 both ways: exact
    }
    for (const auto& cell : cells) {
      int got_type = 0;
      in >> got_type;
      EXPECT_EQ(got_type, type) << what;
      for (int32_t v : cell) {
        int32_t got = -1;
        in >> got;
        EXPECT_EQ(got, v) << what;
      }
    }
  };
  check(cube.points, cube.tets, 10, "cube.vtu");  // VTK_TETRA
  check(octa.points, octa.faces, 5, "octa.vtp");  // VTK_TRIANGLE
  check(octa.points, octa.faces, 5, "octa.vtk");
  EXPECT_FALSE(in.fail());
}

TEST(VtkIo, TriangleStripsKeepTheirOrientation) {
  const auto dir = fresh_test_dir("mesh_io_vtk");
  // A strip 0 1 2 3 over a square: triangles (0 1 2) and (2 1 3), both +z.
  const auto path = write_fixture(dir / "strip.vtk",
                                  "# vtk DataFile Version 3.0\nstrip\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n"
                                  "0 0 0 1 0 0 0 1 0 1 1 0\nTRIANGLE_STRIPS 1 5\n4 0 1 2 3\nPOINT_DATA 4\n");
  const TriangleMesh m = read_surface(path);
  ASSERT_EQ(m.faces.size(), 2u);
  for (const Tri& f : m.faces) {
    const Vec3 n = (m.points[f[1]] - m.points[f[0]]).cross(m.points[f[2]] - m.points[f[0]]);
    EXPECT_GT(n.z(), 0) << f[0] << f[1] << f[2];
  }
}

TEST(VtkIo, CorruptXmlIsAClearErrorBeforeAnythingIsSized) {
  const auto dir = fresh_test_dir("mesh_io_vtk");
  const std::string head = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\">\n<UnstructuredGrid>\n";
  // The piece declares 8 points but the array holds 4 x 3 values.
  std::string few = head + "<Piece NumberOfPoints=\"8\" NumberOfCells=\"1\">\n<Points>\n"
                    "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0 0 0 1</DataArray>\n"
                    "</Points>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  std::string msg = error_message([&] { read_tet_mesh(write_fixture(dir / "few.vtu", few)); });
  EXPECT_NE(msg.find("few.vtu"), std::string::npos) << msg;
  EXPECT_NE(msg.find("holds 12 values, expected 24"), std::string::npos) << msg;
  // A binary header that claims a petabyte.
  std::string huge = head + "<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\">\n<Points>\n"
                     "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">//////////8=</DataArray>\n"
                     "</Points>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  msg = error_message([&] { read_tet_mesh(write_fixture(dir / "huge.vtu", huge)); });
  EXPECT_NE(msg.find("header declares"), std::string::npos) << msg;
  // A declared count far beyond the file.
  std::string absurd = head + "<Piece NumberOfPoints=\"99999999999999999\" NumberOfCells=\"0\">\n";
  msg = error_message([&] { read_tet_mesh(write_fixture(dir / "absurd.vtu", absurd)); });
  EXPECT_NE(msg.find("absurd.vtu"), std::string::npos) << msg;
  // A polydata file is not a tet mesh, and says which it is.
  write_surface(dir / "octa.vtp", octahedron());
  msg = error_message([&] { read_tet_mesh(dir / "octa.vtp"); });
  EXPECT_NE(msg.find("unknown tet mesh extension '.vtp'"), std::string::npos) << msg;
  write_surface(dir / "octa.vtk", octahedron());
  EXPECT_FALSE(is_tet_mesh_path(dir / "octa.vtk"));
  msg = error_message([&] { read_tet_mesh(dir / "octa.vtk"); });
  EXPECT_NE(msg.find("dataset POLYDATA: expected UNSTRUCTURED_GRID"), std::string::npos) << msg;
  // Legacy polydata with an absurd point count.
  msg = error_message([&] {
    read_surface(write_fixture(dir / "count.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 4000000000000 float\n0 0 0\n"));
  });
  EXPECT_NE(msg.find("count.vtk"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cannot fit"), std::string::npos) << msg;
}

TEST(GmshIo, Version1ReadsTheSameCube) {
  const auto dir = fresh_test_dir("mesh_io_vtk");
  const TetMesh cube = five_tet_cube();
  // Node numbers from 11 (not 1-based on purpose), a stray node and a line element.
  std::string s = "$NOD\n" + std::to_string(cube.points.size() + 1) + "\n";
  for (size_t i = 0; i < cube.points.size(); ++i) {
    const Vec3& p = cube.points[i];
    s += std::to_string(11 + i) + " " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  }
  s += "99 5 5 5\n$ENDNOD\n$ELM\n" + std::to_string(cube.tets.size() + 1) + "\n1 1 1 1 2 11 12\n";
  for (size_t t = 0; t < cube.tets.size(); ++t) {
    s += std::to_string(t + 2) + " 4 1 1 4";
    for (int32_t v : cube.tets[t]) s.append(" ").append(std::to_string(11 + v));
    s += "\n";
  }
  s += "$ENDELM\n";
  expect_same_tets(read_tet_mesh(write_fixture(dir / "cube10.msh", s)), cube, "gmsh 1.0");

  // An element whose node count does not fit its type.
  const std::string bad = "$NOD\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$ENDNOD\n$ELM\n1\n1 4 1 1 3 1 2 3\n$ENDELM\n";
  const std::string msg = error_message([&] { read_tet_mesh(write_fixture(dir / "bad10.msh", bad)); });
  EXPECT_NE(msg.find("bad10.msh"), std::string::npos) << msg;
  EXPECT_NE(msg.find("has 3 nodes, expected 4"), std::string::npos) << msg;
}

}  // namespace
}  // namespace mesh_io_vtk_test
}  // namespace organsim
