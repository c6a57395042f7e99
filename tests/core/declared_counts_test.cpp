// Memory is bounded by what the input holds, not by what it declares: a
// header claiming 10^9 elements in a file of a few hundred bytes is refused
// before anything is sized by it, in every format with a count in its header.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "core/mesh/mesh_io.h"
#include "mesh_io_test_util.h"

namespace organsim {
namespace declared_counts_test {
namespace {

struct Claim {
  std::string file;
  std::string text;
  std::string expected;  // in the message, after "FILE: "
};

std::string binary_stl_claiming(uint32_t count) {
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&count), 4);
  s.append(50, '\0');  // one facet actually present
  return s;
}

TEST(DeclaredCounts, ABillionClaimedElementsAreRefusedBeforeAllocating) {
  const std::vector<Claim> claims = {
      {"a.off", "OFF\n1000000000 1 0\n0 0 0\n", "line 2: 1000000000 vertices cannot fit in the rest of the file"},
      {"b.off", "OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "1000000000 faces cannot fit in the rest of the file"},
      {"a.ply", "ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n",
       "element count 1000000000 is negative or larger than the file"},
      {"a.stl", binary_stl_claiming(1000000000), "neither binary STL (size 134 bytes is not 84 + 50 x the facet count"},
      {"a.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1000000000 double\n0 0 0\n",
       "line 5: 1000000000 points cannot fit in the rest of the file"},
      {"b.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 double\n0 0 0\nCELLS 1000000000 5000000000\n",
       "line 7: 5000000000 cell list entry cannot fit in the rest of the file"},
      {"a.mesh", "MeshVersionFormatted 2\nDimension 3\nVertices\n1000000000\n0 0 0 0\n",
       "line 4: 1000000000 vertices cannot fit in the rest of the file"},
      {"b.mesh", "MeshVersionFormatted 2\nDimension 3\nTetrahedra\n1000000000\n1 2 3 4 0\n",
       "line 4: 1000000000 tetrahedra cannot fit in the rest of the file"},
      {"a.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1000000000 1 1000000000\n3 1 0 1000000000\n1\n0 0 0\n$EndNodes\n",
       "line 6: 1000000000 nodes cannot fit in the rest of the file"},
  };
  for (const Claim& c : claims) {
    const std::string msg = testing::error_message([&] {
      if (is_surface_path(c.file)) parse_surface(c.text, c.file);
      else parse_tet_mesh(c.text, c.file);
    });
    EXPECT_EQ(msg.rfind(c.file + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(c.expected), std::string::npos) << "expected: " << c.expected << "\ngot:      " << msg;
  }
}

}  // namespace
}  // namespace declared_counts_test
}  // namespace organsim
