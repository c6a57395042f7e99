// Tet labels through every format: what we write (.mesh references, .vtk and
// .vtu `label` cell arrays) reads back the same and is what VTK reads; what
// VTK writes (XML and legacy, ASCII and binary) and Gmsh physical tags (2.2,
// 4.1) are read as labels.
#include <gtest/gtest.h>

#include <sstream>

#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "mesh_io_test_util.h"
#include "vtk_client.h"

namespace organsim {
namespace mesh_labels_io_test {
namespace {

using testing::error_message;
using testing::five_tet_cube;
using testing::fresh_test_dir;
using testing::run_vtk_python;
using testing::write_fixture;

TetMesh labelled_cube() {
  TetMesh mesh = five_tet_cube();
  mesh.labels = {3, 1, 1, 70000, 2};  // beyond 16 bits too
  return mesh;
}

TEST(MeshLabelsIo, EveryFormatWeWriteKeepsTheLabels) {
  const auto dir = fresh_test_dir("mesh_labels_io");
  const TetMesh mesh = labelled_cube();
  for (const char* name : {"cube.mesh", "cube.vtk", "cube.vtu"}) {
    write_tet_mesh(dir / name, mesh);
    const TetMesh again = read_tet_mesh(dir / name);
    EXPECT_EQ(again.tets, mesh.tets) << name;
    EXPECT_EQ(again.labels, mesh.labels) << name;
  }
  // VTK reads the same label per cell from the XML and the legacy file.
  const std::string out = run_vtk_python(
      "for name, r in (('cube.vtu', vtk.vtkXMLUnstructuredGridReader()), ('cube.vtk', vtk.vtkUnstructuredGridReader())):\n"
      "    r.SetFileName(name)\n    r.Update()\n"
      "    a = r.GetOutput().GetCellData().GetArray('label')\n"
      "    print(a.GetDataTypeAsString(), *[int(a.GetValue(i)) for i in range(a.GetNumberOfTuples())])\n",
      dir);
  EXPECT_EQ(out, "int 3 1 1 70000 2\nint 3 1 1 70000 2\n");
}

TEST(MeshLabelsIo, UnlabelledMeshesStayUnlabelledInVtkFiles) {
  const auto dir = fresh_test_dir("mesh_labels_none");
  const TetMesh mesh = five_tet_cube();
  for (const char* name : {"cube.vtk", "cube.vtu"}) {
    write_tet_mesh(dir / name, mesh);
    EXPECT_TRUE(read_tet_mesh(dir / name).labels.empty()) << name;
  }
  // medit has a reference on every tet: an unlabelled mesh is written as label 1.
  write_tet_mesh(dir / "cube.mesh", mesh);
  EXPECT_EQ(read_tet_mesh(dir / "cube.mesh").labels, std::vector<int32_t>(5, 1));
}

TEST(MeshLabelsIo, ReadsTheLabelsVtkWrites) {
  const auto dir = fresh_test_dir("mesh_labels_vtk");
  const TetMesh mesh = labelled_cube();
  std::ostringstream s;
  s.precision(17);
  s << "pts = vtk.vtkPoints()\n";
  for (const Vec3& p : mesh.points) s << "pts.InsertNextPoint(" << p.x() << ", " << p.y() << ", " << p.z() << ")\n";
  s << "g = vtk.vtkUnstructuredGrid()\ng.SetPoints(pts)\n";
  for (const Tet& t : mesh.tets) s << "g.InsertNextCell(10, 4, [" << t[0] << ", " << t[1] << ", " << t[2] << ", " << t[3] << "])\n";
  s << "a = vtk.vtkIntArray()\na.SetName('label')\n";
  for (int32_t l : mesh.labels) s << "a.InsertNextValue(" << l << ")\n";
  s << "g.GetCellData().AddArray(a)\n"
       "d = vtk.vtkDoubleArray()\nd.SetName('stress')\nd.SetNumberOfComponents(3)\n"
       "[d.InsertNextTuple3(i, 2 * i, 3 * i) for i in range(5)]\ng.GetCellData().AddArray(d)\n"
       "for name, mode in (('ascii.vtu', 'Ascii'), ('binary.vtu', 'Binary')):\n"
       "    w = vtk.vtkXMLUnstructuredGridWriter(); w.SetFileName(name); w.SetInputData(g)\n"
       "    w.SetCompressorTypeToNone(); getattr(w, 'SetDataModeTo' + mode)(); assert w.Write() == 1\n"
       "for name, binary in (('ascii.vtk', False), ('binary.vtk', True)):\n"
       "    w = vtk.vtkUnstructuredGridWriter(); w.SetFileName(name); w.SetInputData(g)\n"
       "    if binary: w.SetFileTypeToBinary()\n"
       "    w.Write()\n";
  run_vtk_python(s.str(), dir);
  for (const char* name : {"ascii.vtu", "binary.vtu", "ascii.vtk", "binary.vtk"}) {
    const TetMesh got = read_tet_mesh(dir / name);
    EXPECT_EQ(got.labels, mesh.labels) << name;
  }
}

TEST(MeshLabelsIo, GmshPhysicalTagsAreLabels) {
  const auto dir = fresh_test_dir("mesh_labels_gmsh");
  const std::string nodes22 = "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n";
  write_fixture(dir / "two.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n" + nodes22 +
                                     "$Elements\n3\n1 2 2 9 1 1 2 3\n2 4 2 7 1 1 2 3 4\n3 4 2 8 2 2 5 3 4\n$EndElements\n");
  EXPECT_EQ(read_tet_mesh(dir / "two.msh").labels, (std::vector<int32_t>{7, 8}));
  // 4.1: a volume's physical tag is in $Entities.
  write_fixture(dir / "two41.msh",
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                "$Entities\n0 0 0 2\n1 0 0 0 1 1 1 1 11 0\n2 0 0 0 1 1 1 1 12 0\n$EndEntities\n"
                "$Nodes\n1 5 1 5\n3 1 0 5\n1\n2\n3\n4\n5\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n$EndNodes\n"
                "$Elements\n2 2 1 2\n3 1 4 1\n1 1 2 3 4\n3 2 4 1\n2 2 5 3 4\n$EndElements\n");
  EXPECT_EQ(read_tet_mesh(dir / "two41.msh").labels, (std::vector<int32_t>{11, 12}));
  // Without physical tags: no labels.
  write_fixture(dir / "bare.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n" + nodes22 +
                                      "$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n");
  EXPECT_TRUE(read_tet_mesh(dir / "bare.msh").labels.empty());
}

TEST(MeshLabelsIo, NonIntegerLabelsAreErrorsNamingTheCell) {
  const auto dir = fresh_test_dir("mesh_labels_bad");
  std::ostringstream vtk;
  vtk << "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
         "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nCELL_DATA 1\nSCALARS label float 1\nLOOKUP_TABLE default\n1.5\n";
  write_fixture(dir / "half.vtk", vtk.str());
  const std::string message = error_message([&] { read_tet_mesh(dir / "half.vtk"); });
  EXPECT_NE(message.find("half.vtk: line"), std::string::npos) << message;
  EXPECT_NE(message.find("cell 0 has label 1.5"), std::string::npos) << message;
}

}  // namespace
}  // namespace mesh_labels_io_test
}  // namespace organsim
