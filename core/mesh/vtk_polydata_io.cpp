// VTK legacy polydata surfaces: ASCII or BINARY, classic or 5.1 cell layout.
// POLYGONS of three points and TRIANGLE_STRIPS (split into triangles) make the
// surface; VERTICES and LINES are read past; a polygon of more than three
// points is refused (fan-splitting a non-convex polygon would fold it). The
// attribute sections after the geometry (POINT_DATA, CELL_DATA) are not read.
#include <ostream>
#include <vector>

#include "core/mesh/vtk_legacy.h"

namespace organsim::mesh_io {

namespace {

Tri checked_triangle(TokenReader& in, const std::vector<int64_t>& ids, size_t npoint, const std::string& what) {
  Tri tri{};
  for (int k = 0; k < 3; ++k) {
    if (ids[k] < 0 || ids[k] >= static_cast<int64_t>(npoint)) {
      in.fail(what + " refers to point " + std::to_string(ids[k]) + ", expected an index in [0, " +
              std::to_string(npoint) + ")");
    }
    tri[k] = static_cast<int32_t>(ids[k]);
  }
  return tri;
}

}  // namespace

TriangleMesh read_vtk_polydata(std::string_view bytes, const std::string& source) {
  TokenReader in(bytes, source, 0);
  bool binary = false;
  const std::string dataset = read_vtk_legacy_header(in, binary);
  if (dataset != "POLYDATA") in.fail("dataset " + dataset + ": expected POLYDATA (a triangle surface)");
  VtkValues values(in, bytes, binary);
  TriangleMesh mesh;
  bool have_points = false, have_polys = false;
  while (!in.at_end()) {
    const std::string keyword(in.next("a section keyword"));
    if (keyword == "POINTS") {
      mesh.points = read_vtk_points(in, values);
      have_points = true;
    } else if (keyword == "POLYGONS" || keyword == "TRIANGLE_STRIPS" || keyword == "VERTICES" || keyword == "LINES") {
      const auto cells = read_vtk_cell_list(in, values, keyword, in.next_int("the cell count"));
      if (keyword == "POLYGONS") {
        for (size_t c = 0; c < cells.size(); ++c) {
          const std::string name = "polygon " + std::to_string(c);
          if (cells[c].size() != 3) in.fail(not_a_triangle(c, cells[c].size()));
          mesh.faces.push_back(checked_triangle(in, cells[c], mesh.points.size(), name));
        }
        have_polys = true;
      } else if (keyword == "TRIANGLE_STRIPS") {
        // Strip (p0 p1 p2 p3 ...): triangle j is (j, j+1, j+2), every other one
        // reversed so that all keep the strip's orientation.
        for (size_t c = 0; c < cells.size(); ++c) {
          const auto& s = cells[c];
          for (size_t j = 0; j + 2 < s.size(); ++j) {
            const std::vector<int64_t> ids = j % 2 == 0 ? std::vector<int64_t>{s[j], s[j + 1], s[j + 2]}
                                                       : std::vector<int64_t>{s[j + 1], s[j], s[j + 2]};
            mesh.faces.push_back(checked_triangle(in, ids, mesh.points.size(), "triangle strip " + std::to_string(c)));
          }
        }
        have_polys = true;
      }
    } else if (keyword == "FIELD") {
      skip_vtk_field(in, values);
    } else if (keyword == "METADATA") {
      skip_vtk_metadata(in);
    } else if (keyword == "POINT_DATA" || keyword == "CELL_DATA") {
      break;  // attributes: nothing the surface needs
    } else {
      in.fail("unexpected '" + keyword + "', expected POINTS, POLYGONS, TRIANGLE_STRIPS, VERTICES, LINES or POINT_DATA");
    }
  }
  if (!have_points) throw input_error(source, "missing POINTS section");
  if (!have_polys) throw input_error(source, "no POLYGONS or TRIANGLE_STRIPS: the file holds no surface");
  return mesh;
}

void write_vtk_polydata(std::ostream& out, const TriangleMesh& mesh) {
  out << "# vtk DataFile Version 3.0\norgansim surface\nASCII\nDATASET POLYDATA\n";
  out << "POINTS " << mesh.points.size() << " double\n";
  for (const Vec3& p : mesh.points) {
    write_point(out, p);
    out << '\n';
  }
  out << "POLYGONS " << mesh.faces.size() << ' ' << 4 * mesh.faces.size() << '\n';
  for (const Tri& f : mesh.faces) out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
}

}  // namespace organsim::mesh_io
