// Every error path of the tet mesh readers (VTK legacy, Gmsh .msh, medit
// .mesh): a small valid file broken in one place gives the error for that
// place, naming the file and the line. The valid files read first, so each
// case fails only for the one thing changed.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/mesh/mesh_io.h"
#include "mesh_io_test_util.h"

namespace organsim {
namespace tet_reader_errors_test {
namespace {

// Two positively oriented tets on five points, in each format.
const std::string kVtk =
    "# vtk DataFile Version 3.0\ntwo tets\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 double\n"
    "0 0 0\n0.1 0 0\n0 0.1 0\n0 0 0.1\n0.1 0.1 0.1\nCELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\nCELL_TYPES 2\n10\n10\n";
const std::string kMsh22 =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 0.1 0 0\n3 0 0.1 0\n4 0 0 0.1\n5 0.1 0.1 0.1\n"
    "$EndNodes\n$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 2 3 4 5\n$EndElements\n";
const std::string kMsh41 =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 5 1 5\n3 1 0 5\n1\n2\n3\n4\n5\n"
    "0 0 0\n0.1 0 0\n0 0.1 0\n0 0 0.1\n0.1 0.1 0.1\n$EndNodes\n$Elements\n1 2 1 2\n3 1 4 2\n1 1 2 3 4\n2 2 3 4 5\n"
    "$EndElements\n";
const std::string kMedit =
    "MeshVersionFormatted 2\nDimension 3\nVertices\n5\n0 0 0 0\n0.1 0 0 0\n0 0.1 0 0\n0 0 0.1 0\n0.1 0.1 0.1 0\n"
    "Tetrahedra\n2\n1 2 3 4 1\n2 3 4 5 1\nEnd\n";

// `base` with its first `from` replaced by `to`.
std::string with(const std::string& base, const std::string& from, const std::string& to) {
  const size_t at = base.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  std::string s = base;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

struct Case {
  std::string file;      // the extension picks the reader
  std::string text;
  std::string expected;  // in the message, after "FILE: "
};

TEST(TetReaderErrors, TheUnbrokenFilesRead) {
  for (const auto& [file, text] : std::vector<std::pair<std::string, std::string>>{
           {"a.vtk", kVtk}, {"a.msh", kMsh22}, {"b.msh", kMsh41}, {"a.mesh", kMedit}}) {
    const TetMesh mesh = parse_tet_mesh(text, file);
    EXPECT_EQ(mesh.points.size(), 5u) << file;
    EXPECT_EQ(mesh.tets.size(), 2u) << file;
  }
}

TEST(TetReaderErrors, EachBrokenPlaceIsNamed) {
  const std::vector<Case> cases = {
      // VTK legacy
      {"v.vtk", with(kVtk, "# vtk DataFile", "# not a"), "line 1: expected '# vtk DataFile Version ...'"},
      {"v.vtk", with(kVtk, "ASCII", "TEXT"), "line 3: expected ASCII or BINARY, got 'TEXT'"},
      {"v.vtk", with(kVtk, "DATASET UNSTRUCTURED_GRID", "GRID"), "line 4: expected 'DATASET UNSTRUCTURED_GRID'"},
      {"v.vtk", with(kVtk, "UNSTRUCTURED_GRID", "STRUCTURED_POINTS"),
       "line 4: dataset STRUCTURED_POINTS: expected UNSTRUCTURED_GRID"},
      {"v.vtk", with(kVtk, "POINTS 5", "POINTS five"), "line 5: expected the point count (an integer), got 'five'"},
      {"v.vtk", with(kVtk, "POINTS 5", "POINTS -5"), "line 5: negative points -5"},
      {"v.vtk", with(kVtk, "POINTS 5", "POINTS 500"), "line 5: 500 points cannot fit in the rest of the file"},
      {"v.vtk", with(kVtk, "0.1 0.1 0.1", "0.1 0.1 z"), "line 10: expected point coordinate (a number), got 'z'"},
      {"v.vtk", with(with(kVtk, "ASCII", "BINARY"), "POINTS 5 double", "POINTS 5 bit"),
       "line 5: unsupported binary data type 'bit'"},
      {"v.vtk", with(kVtk, "ASCII", "BINARY").substr(0, kVtk.find("0 0 0\n") + 40),  // 40 of 120 bytes
       "line 6: file ends inside the binary point coordinate"},  // the binary data starts on line 6
      {"v.vtk", with(kVtk, "CELLS 2 10", "CELLS 2 11"), "line 14: expected cell list entry (a number), got 'CELL_TYPES'"},
      {"v.vtk", with(kVtk, "4 1 2 3 4", "9 1 2 3 4"), "line 13: cell 1 has an invalid point count 9"},
      {"v.vtk", with(kVtk, "CELLS 2 10\n4 0 1 2 3\n4 1 2 3 4", "CELLS 3 10\n4 0 1 2 3\n4 1 2 3 4"),
       "CELLS list is shorter than its 3 cells"},
      {"v.vtk", with(kVtk, "CELL_TYPES 2", "CELL_TYPES 3"), "line 14: CELL_TYPES has 3 entries, expected one per cell (2)"},
      {"v.vtk", with(kVtk, "4 1 2 3 4", "3 1 2 3 4"), "tetra cell 1 has 3 points, expected 4"},
      {"v.vtk", with(kVtk, "4 1 2 3 4", "4 1 2 3 9"), "tetrahedron 1 (cell 1) has vertex index 9, expected 0..4"},
      {"v.vtk", with(kVtk, "10\n10\n", "10\n12\n"), "cell 1 has VTK type 12, expected 10 (tetra)"},
      {"v.vtk", with(kVtk, "POINTS", "SCALARS"), "line 5: unexpected 'SCALARS' before POINTS, CELLS and CELL_TYPES"},
      {"v.vtk", kVtk.substr(0, kVtk.find("CELL_TYPES")), "missing POINTS, CELLS or CELL_TYPES section"},
      {"v.vtk",
       with(kVtk, "CELLS 2 10\n4 0 1 2 3\n4 1 2 3 4",
            "CELLS 3 8\nOFFSETS vtktypeint64\n0 4 8\nCONNECTIVITY vtktypeint64\n0 1 2 3 1 2 3 4"),
       ""},  // the 5.1 layout reads: checked below by the next two
      {"v.vtk",
       with(kVtk, "CELLS 2 10\n4 0 1 2 3\n4 1 2 3 4",
            "CELLS 3 8\nOFFSETS vtktypeint64\n0 4 8\nLINKS vtktypeint64\n0 1 2 3 1 2 3 4"),
       "line 14: expected CONNECTIVITY"},
      {"v.vtk",
       with(kVtk, "CELLS 2 10\n4 0 1 2 3\n4 1 2 3 4",
            "CELLS 3 8\nOFFSETS vtktypeint64\n0 4 9\nCONNECTIVITY vtktypeint64\n0 1 2 3 1 2 3 4"),
       "cell 1: offsets out of range"},
      {"v.vtk", kVtk + "FIELD", ""},  // after the three sections the rest is not read
      // Gmsh 2.2 and 4.1
      {"g.msh", with(kMsh22, "$MeshFormat", "$Mesh"), "line 1: expected $MeshFormat, got '$Mesh'"},
      {"g.msh", with(kMsh22, "2.2 0 8", "2.2 1 8"), "line 2: binary .msh is not supported"},
      {"g.msh", with(kMsh22, "2.2 0 8", "3.0 0 8"), "line 2: MSH version 3.0: expected 2.2 or 4.1"},
      {"g.msh", with(kMsh22, "2 0.1 0 0", "1 0.1 0 0"), "line 7: node 1 is defined twice"},
      {"g.msh", with(kMsh22, "1 4 2 1 1", "1 99 2 1 1"), "line 14: unsupported element type 99"},
      {"g.msh", with(kMsh22, "$EndNodes", "$End"), "line 11: expected $EndNodes, got '$End'"},
      {"g.msh", with(kMsh22, "$Nodes", "$PhysicalNames\n1\n3 1 \"x\"\n$Nodes"), "section $PhysicalNames has no $EndPhysicalNames"},
      {"g.msh", with(kMsh22, "$Nodes", "Nodes"), "line 4: expected a $Section, got 'Nodes'"},
      {"g.msh", with(kMsh22, "2 4 2 1 1 2 3 4 5", "2 4 2 1 1 2 3 4 7"), "line 15: tetrahedron 1 refers to node 7, which is not in $Nodes"},
      {"g.msh", with(kMsh22, "5 0.1 0.1 0.1", "5 0.1 0.1 y"), "line 10: expected a node z (a number), got 'y'"},
      {"g.msh", with(kMsh41, "3 1 0 5", "3 1 0 500"), "line 6: 500 nodes cannot fit in the rest of the file"},
      {"g.msh", with(kMsh41, "1 1 2 3 4", "1 1 2 3 9"), "tetrahedron 0 refers to node 9, which is not in $Nodes"},
      {"g.msh", with(kMsh41, "3 1 4 2\n1 1 2 3 4\n2 2 3 4 5", "3 1 2 2\n1 1 2 3\n2 2 3 4"), "no tetrahedra"},
      // medit
      {"m.mesh", with(kMedit, "Dimension 3", "Dimension 2"), "line 2: Dimension 2: expected 3"},
      {"m.mesh", with(kMedit, "Vertices\n5", "Vertices\n500"), "line 4: 500 vertices cannot fit in the rest of the file"},
      {"m.mesh", with(kMedit, "Vertices\n5", "Vertices\n-5"), "line 4: negative vertices -5"},
      {"m.mesh", with(kMedit, "0.1 0 0 0", "abc 0 0 0"), "line 6: expected a vertex x coordinate (a number), got 'abc'"},
      {"m.mesh", with(kMedit, "2 3 4 5 1", "2 3 4 9 1"),
       "line 13: tetrahedron 1 refers to vertex 9, expected an index in [1, 5] (medit counts from 1)"},
      {"m.mesh", with(kMedit, "Tetrahedra", "Pyramids"), "line 10: unknown medit section 'Pyramids'"},
      {"m.mesh", with(kMedit, "2 3 4 5 1\nEnd\n", "2 3 4 5\n# reference missing\n"),
       "line 15: expected a tetrahedron reference, got the end of the file"},
      {"m.mesh", with(kMedit, "2 3 4 5 1", "2 3 4 4 1"), "tetrahedron 1 has zero volume"},
      {"m.mesh", with(kMedit, "2 3 4 5 1", "2 3 5 4 1"), "tetrahedron 1 is inverted"},
  };
  for (const Case& c : cases) {
    if (c.expected.empty()) {
      EXPECT_NO_THROW(parse_tet_mesh(c.text, c.file)) << c.text;
      continue;
    }
    const std::string msg = testing::error_message([&] { parse_tet_mesh(c.text, c.file); });
    EXPECT_EQ(msg.rfind(c.file + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(c.expected), std::string::npos) << "expected: " << c.expected << "\ngot:      " << msg;
  }
}

}  // namespace
}  // namespace tet_reader_errors_test
}  // namespace organsim
