// medit .mesh (INRIA) tet meshes, ASCII: Vertices and Tetrahedra are used;
// the other known sections are read past. Indices in the file start at 1.
// A tet's reference is its label (TetMesh::labels).
#include <cstdint>
#include <ostream>

#include "core/mesh/mesh_io_detail.h"
#include "core/mesh/mesh_stats.h"

namespace organsim::mesh_io {

namespace {
// Sections we read past: number of integers/reals per entry.
struct SkippedSection {
  const char* name;
  int values;
};
constexpr SkippedSection kSkipped[] = {
    {"Edges", 3},        {"Triangles", 4},       {"Quadrilaterals", 5}, {"Hexahedra", 9},
    {"Prisms", 7},       {"Corners", 1},         {"RequiredVertices", 1}, {"Ridges", 1},
    {"RequiredEdges", 1}, {"RequiredTriangles", 1}, {"Normals", 3},     {"NormalAtVertices", 2},
    {"Tangents", 3},     {"TangentAtVertices", 2}, {"Identifier", 0},  {"Geometry", 0}};
}  // namespace

TetMesh read_medit(std::string_view text, const std::string& source) {
  TokenReader in(text, source);
  TetMesh mesh;
  bool have_vertices = false;
  while (!in.at_end()) {
    const std::string keyword(in.next("a section keyword"));
    if (keyword == "End") break;
    if (keyword == "MeshVersionFormatted") {
      in.next_int("the format version");
    } else if (keyword == "Dimension") {
      const int64_t d = in.next_int("the dimension");
      if (d != 3) in.fail("Dimension " + std::to_string(d) + ": expected 3");
    } else if (keyword == "Vertices") {
      const int64_t n = in.checked_count(in.next_int("the vertex count"), 8, "vertices");
      mesh.points.reserve(static_cast<size_t>(n));
      for (int64_t i = 0; i < n; ++i) {
        const double x = in.next_double("a vertex x coordinate");
        const double y = in.next_double("a vertex y coordinate");
        const double z = in.next_double("a vertex z coordinate");
        in.next_int("a vertex reference");
        mesh.points.emplace_back(x, y, z);
      }
      have_vertices = true;
    } else if (keyword == "Tetrahedra") {
      const int64_t n = in.checked_count(in.next_int("the tetrahedron count"), 10, "tetrahedra");
      mesh.tets.reserve(static_cast<size_t>(n));
      const auto nv = static_cast<int64_t>(mesh.points.size());
      for (int64_t t = 0; t < n; ++t) {
        Tet tet{};
        for (int k = 0; k < 4; ++k) {
          const int64_t v = in.next_int("a tetrahedron vertex index");
          if (have_vertices && (v < 1 || v > nv)) {
            in.fail("tetrahedron " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                    ", expected an index in [1, " + std::to_string(nv) + "] (medit counts from 1)");
          }
          tet[k] = static_cast<int32_t>(v - 1);
        }
        const int64_t ref = in.next_int("a tetrahedron reference");
        if (ref < INT32_MIN || ref > INT32_MAX) in.fail("tetrahedron " + std::to_string(t) + " has reference " + std::to_string(ref) + ", beyond a 32-bit label");
        mesh.tets.push_back(tet);
        mesh.labels.push_back(static_cast<int32_t>(ref));
      }
    } else {
      const SkippedSection* section = nullptr;
      for (const auto& s : kSkipped) {
        if (keyword == s.name) section = &s;
      }
      if (section == nullptr) in.fail("unknown medit section '" + keyword + "'");
      if (section->values == 0) {
        in.skip_line();
        continue;
      }
      const int64_t n = in.checked_count(in.next_int("the entry count"), 2 * section->values, "entries");
      for (int64_t i = 0; i < n * section->values; ++i) in.next(section->name);
    }
  }
  return mesh;
}

void write_medit(std::ostream& out, const TetMesh& mesh) {
  out << "MeshVersionFormatted 2\nDimension 3\n";
  out << "# organsim tet mesh, metres; indices count from 1\n";
  out << "Vertices\n" << mesh.points.size() << '\n';
  for (const Vec3& p : mesh.points) {
    write_point(out, p);
    out << " 0\n";
  }
  // The boundary triangles too, so viewers (medit, gmsh, meshlab) show the surface.
  const std::vector<Tri> boundary = boundary_triangles(mesh);
  out << "Triangles\n" << boundary.size() << '\n';
  for (const Tri& f : boundary) out << f[0] + 1 << ' ' << f[1] + 1 << ' ' << f[2] + 1 << " 1\n";
  out << "Tetrahedra\n" << mesh.tets.size() << '\n';
  // A tet's reference is its label (1 for an unlabelled mesh).
  for (size_t i = 0; i < mesh.tets.size(); ++i) {
    const Tet& t = mesh.tets[i];
    out << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << ' ' << t[3] + 1 << ' '
        << (mesh.labels.empty() ? 1 : mesh.labels[i]) << '\n';
  }
  out << "End\n";
}

}  // namespace organsim::mesh_io
