// VTK legacy unstructured grids of tets: ASCII or BINARY (big endian), the
// classic CELLS layout and the 5.1 OFFSETS/CONNECTIVITY layout. Cells of type
// 10 (tetra) are kept; vertices, lines and triangles (1, 3, 5) are read past.
// A cell array `label` (SCALARS or FIELD, int or any number type holding
// whole numbers) is each tet's label.
#include <ostream>
#include <vector>

#include "core/mesh/vtk_legacy.h"

namespace organsim::mesh_io {

namespace {

// The cell array `label` (a SCALARS attribute or a FIELD array of CELL_DATA)
// after the geometry, when the file has one. Reading stops at the first
// section that is not cell data: other attributes are not needed.
void read_cell_labels(TokenReader& in, VtkValues& values, int64_t ncell, const std::vector<int64_t>& tet_cells,
                      TetMesh& mesh) {
  if (in.at_end() || in.peek() != "CELL_DATA") return;
  in.next("CELL_DATA");
  const int64_t n = in.next_int("the cell data count");
  if (n != ncell) in.fail("CELL_DATA has " + std::to_string(n) + " entries, expected one per cell (" + std::to_string(ncell) + ")");
  const auto take = [&](const std::vector<double>& v) {
    mesh.labels.clear();
    for (int64_t c : tet_cells) {
      int32_t label = 0;
      if (!label_from_value(v[static_cast<size_t>(c)], label)) {
        in.fail("cell " + std::to_string(c) + " has label " + std::to_string(v[static_cast<size_t>(c)]) + ", expected a 32-bit integer");
      }
      mesh.labels.push_back(label);
    }
  };
  // VTK 9 follows an array with a METADATA block.
  const auto skip_metadata = [&] {
    if (!in.at_end() && in.peek() == "METADATA") {
      in.next("METADATA");
      skip_vtk_metadata(in);
    }
  };
  while (!in.at_end()) {
    const std::string_view keyword = in.peek();
    if (keyword == "SCALARS") {
      in.next("SCALARS");
      const std::string name(in.next("the array name"));
      const std::string type(in.next("the array type"));
      int64_t components = 1;
      if (in.peek() != "LOOKUP_TABLE") {
        // An optional component count on the same line.
        int64_t given = 0;
        if (parse_int(in.peek(), given)) components = in.checked_count(in.next_int("the component count"), 1, "components");
      }
      if (in.peek() == "LOOKUP_TABLE") {
        in.next("LOOKUP_TABLE");
        in.next("the lookup table name");
      }
      const auto v = values.read(n * components, type, "cell value");
      if (name == "label" && components == 1) take(v);
      skip_metadata();
    } else if (keyword == "FIELD") {
      in.next("FIELD");
      in.next("the field name");
      const int64_t arrays = in.next_int("the field array count");
      for (int64_t a = 0; a < arrays; ++a) {
        const std::string name(in.next("an array name"));
        const int64_t components = in.checked_count(in.next_int("the component count"), 1, "components");
        const int64_t tuples = in.checked_count(in.next_int("the tuple count"), 1, "tuples");
        const std::string type(in.next("the array type"));
        const auto v = values.read(components * tuples, type, "field value");
        if (name == "label" && components == 1 && tuples == ncell) take(v);
        skip_metadata();
      }
    } else {
      return;
    }
  }
}

}  // namespace

TetMesh read_vtk(std::string_view bytes, const std::string& source) {
  TokenReader in(bytes, source, 0);
  bool binary = false;
  const std::string dataset = read_vtk_legacy_header(in, binary);
  if (dataset != "UNSTRUCTURED_GRID") {
    in.fail("dataset " + dataset + ": expected UNSTRUCTURED_GRID (a tetrahedral mesh)");
  }
  VtkValues values(in, bytes, binary);
  TetMesh mesh;
  std::vector<std::vector<int64_t>> cells;
  std::vector<int64_t> tet_cells;  // the cell each tet is
  bool have_points = false, have_cells = false, have_types = false;
  while (!in.at_end() && !(have_points && have_cells && have_types)) {
    const std::string keyword(in.next("a section keyword"));
    if (keyword == "POINTS") {
      mesh.points = read_vtk_points(in, values);
      have_points = true;
    } else if (keyword == "CELLS") {
      cells = read_vtk_cell_list(in, values, keyword, in.next_int("the cell count"));
      have_cells = true;
    } else if (keyword == "CELL_TYPES") {
      const int64_t n = in.next_int("the cell type count");
      if (static_cast<size_t>(n) != cells.size()) {
        in.fail("CELL_TYPES has " + std::to_string(n) + " entries, expected one per cell (" +
                std::to_string(cells.size()) + ")");
      }
      const auto types = values.read(n, "int", "cell type");
      for (int64_t c = 0; c < n; ++c) {
        const int64_t type = vtk_index(types[c]);
        if (type == 10) {
          if (cells[c].size() != 4) in.fail("tetra cell " + std::to_string(c) + " has " + std::to_string(cells[c].size()) + " points, expected 4");
          for (int64_t v : cells[c]) {
            if (v < 0 || v >= static_cast<int64_t>(mesh.points.size())) {
              in.fail("tetrahedron " + std::to_string(mesh.tets.size()) + " (cell " + std::to_string(c) + ") has vertex index " +
                      std::to_string(v) + ", expected 0.." + std::to_string(static_cast<int64_t>(mesh.points.size()) - 1));
            }
          }
          tet_cells.push_back(c);
          mesh.tets.push_back({static_cast<int32_t>(cells[c][0]), static_cast<int32_t>(cells[c][1]),
                               static_cast<int32_t>(cells[c][2]), static_cast<int32_t>(cells[c][3])});
        } else if (type != 1 && type != 3 && type != 5) {
          in.fail("cell " + std::to_string(c) + " has VTK type " + std::to_string(type) +
                  ", expected 10 (tetra); only linear tetrahedral meshes are supported");
        }
      }
      have_types = true;
    } else if (keyword == "FIELD") {
      skip_vtk_field(in, values);
    } else if (keyword == "METADATA") {
      skip_vtk_metadata(in);
    } else {
      in.fail("unexpected '" + keyword + "' before POINTS, CELLS and CELL_TYPES were read");
    }
  }
  if (!have_points || !have_cells || !have_types) {
    throw input_error(source, "missing POINTS, CELLS or CELL_TYPES section");
  }
  read_cell_labels(in, values, static_cast<int64_t>(cells.size()), tet_cells, mesh);
  return mesh;
}

void write_vtk(std::ostream& out, const TetMesh& mesh) {
  out << "# vtk DataFile Version 3.0\norgansim tet mesh, metres\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  out << "POINTS " << mesh.points.size() << " double\n";
  for (const Vec3& p : mesh.points) {
    write_point(out, p);
    out << '\n';
  }
  out << "CELLS " << mesh.tets.size() << ' ' << 5 * mesh.tets.size() << '\n';
  for (const Tet& t : mesh.tets) out << "4 " << t[0] << ' ' << t[1] << ' ' << t[2] << ' ' << t[3] << '\n';
  out << "CELL_TYPES " << mesh.tets.size() << '\n';
  for (size_t i = 0; i < mesh.tets.size(); ++i) out << "10\n";
  if (!mesh.labels.empty()) {
    out << "CELL_DATA " << mesh.tets.size() << "\nSCALARS label int 1\nLOOKUP_TABLE default\n";
    for (int32_t label : mesh.labels) out << label << '\n';
  }
}

}  // namespace organsim::mesh_io
