// VTK legacy unstructured grids of tets: ASCII or BINARY (big endian), the
// classic CELLS layout and the 5.1 OFFSETS/CONNECTIVITY layout. Cells of type
// 10 (tetra) are kept; vertices, lines and triangles (1, 3, 5) are read past.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <ostream>
#include <vector>

#include "core/mesh/mesh_io_detail.h"

namespace organsim::mesh_io {

namespace {

int type_size(std::string_view type) {
  if (type == "float") return 4;
  if (type == "double") return 8;
  if (type == "int" || type == "vtktypeint32") return 4;
  if (type == "vtktypeint64" || type == "long") return 8;
  return 0;
}

// Reads numbers either as ASCII tokens or as big-endian binary values.
class VtkValues {
 public:
  VtkValues(TokenReader& in, std::string_view bytes, bool binary) : in_(in), bytes_(bytes), binary_(binary) {}

  // Reads n values of `type`; in binary mode they start after the current line.
  std::vector<double> read(int64_t n, std::string_view type, const char* what) {
    in_.checked_count(n, binary_ ? 1 : 2, what);
    std::vector<double> values;
    values.reserve(static_cast<size_t>(n));
    if (!binary_) {
      for (int64_t i = 0; i < n; ++i) values.push_back(in_.next_double(what));
      return values;
    }
    const int size = type_size(type);
    if (size == 0) in_.fail("unsupported binary data type '" + std::string(type) + "'");
    in_.skip_line();
    size_t pos = in_.position();
    if (pos + static_cast<size_t>(n) * static_cast<size_t>(size) > bytes_.size()) {
      in_.fail(std::string("file ends inside the binary ") + what);
    }
    for (int64_t i = 0; i < n; ++i, pos += static_cast<size_t>(size)) {
      unsigned char raw[8];
      std::memcpy(raw, bytes_.data() + pos, static_cast<size_t>(size));
      if (std::endian::native == std::endian::little) {  // byte order of the file differs from the host's
        unsigned char swapped[8];
        for (int b = 0; b < size; ++b) swapped[b] = raw[size - 1 - b];
        std::memcpy(raw, swapped, sizeof raw);
      }
      const bool is_float = type == "float" || type == "double";
      if (size == 4 && is_float) { float v; std::memcpy(&v, raw, 4); values.push_back(v); }
      else if (size == 8 && is_float) { double v; std::memcpy(&v, raw, 8); values.push_back(v); }
      else if (size == 4) { int32_t v; std::memcpy(&v, raw, 4); values.push_back(v); }
      else { int64_t v; std::memcpy(&v, raw, 8); values.push_back(static_cast<double>(v)); }
    }
    in_.set_position(pos, in_.line());
    return values;
  }

 private:
  TokenReader& in_;
  std::string_view bytes_;
  bool binary_;
};

// Point ids as integers; anything that is not a representable whole number
// becomes -1 and fails the range check with the cell named.
int64_t to_index(double v) { return v >= 0 && v < 9.0e15 && v == std::floor(v) ? static_cast<int64_t>(v) : -1; }

std::vector<int64_t> to_indices(std::vector<double>::const_iterator begin, std::vector<double>::const_iterator end) {
  std::vector<int64_t> ids;
  for (auto it = begin; it != end; ++it) ids.push_back(to_index(*it));
  return ids;
}

}  // namespace

TetMesh read_vtk(std::string_view bytes, const std::string& source) {
  TokenReader in(bytes, source, 0);
  const std::string_view first = in.rest_of_line();
  if (first.find("vtk DataFile") == std::string_view::npos) {
    throw input_error(source, "line 1: expected '# vtk DataFile Version ...' (VTK legacy format)");
  }
  in.rest_of_line();  // title
  const std::string_view encoding = in.next("ASCII or BINARY");
  if (encoding != "ASCII" && encoding != "BINARY") in.fail("expected ASCII or BINARY, got '" + std::string(encoding) + "'");
  VtkValues values(in, bytes, encoding == "BINARY");
  if (in.next("DATASET") != "DATASET") in.fail("expected 'DATASET UNSTRUCTURED_GRID'");
  const std::string_view dataset = in.next("the dataset type");
  if (dataset != "UNSTRUCTURED_GRID") {
    in.fail("dataset " + std::string(dataset) + ": expected UNSTRUCTURED_GRID (a tetrahedral mesh)");
  }
  TetMesh mesh;
  std::vector<std::vector<int64_t>> cells;
  bool have_points = false, have_cells = false, have_types = false;
  while (!in.at_end() && !(have_points && have_cells && have_types)) {
    const std::string keyword(in.next("a section keyword"));
    if (keyword == "POINTS") {
      // Checked before 3 * n, which could overflow.
      const int64_t n = in.checked_count(in.next_int("the point count"), 3, "points");
      const std::string type(in.next("the point data type"));
      const auto xyz = values.read(3 * n, type, "point coordinate");
      for (int64_t i = 0; i < n; ++i) mesh.points.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
      have_points = true;
    } else if (keyword == "CELLS") {
      const int64_t n = in.next_int("the cell count");
      const int64_t size = in.next_int("the cell list size");
      if (in.peek() == "OFFSETS") {  // VTK 5.1: n offsets (cells + 1) and `size` indices
        in.next("OFFSETS");
        const std::string otype(in.next("the offsets type"));
        const auto offsets = values.read(n, otype, "cell offset");
        if (in.next("CONNECTIVITY") != "CONNECTIVITY") in.fail("expected CONNECTIVITY");
        const std::string ctype(in.next("the connectivity type"));
        const auto ids = values.read(size, ctype, "cell connectivity index");
        for (int64_t c = 0; c + 1 < n; ++c) {
          const int64_t begin = to_index(offsets[c]), end = to_index(offsets[c + 1]);
          if (begin < 0 || end < begin || end > size) in.fail("cell " + std::to_string(c) + ": offsets out of range");
          cells.push_back(to_indices(ids.begin() + begin, ids.begin() + end));
        }
      } else {
        const auto list = values.read(size, "int", "cell list entry");
        size_t k = 0;
        for (int64_t c = 0; c < n; ++c) {
          if (k >= list.size()) in.fail("CELLS list is shorter than its " + std::to_string(n) + " cells");
          const int64_t count = to_index(list[k++]);
          if (count < 0 || k + static_cast<size_t>(count) > list.size()) {
            in.fail("cell " + std::to_string(c) + " has an invalid point count " + std::to_string(count));
          }
          cells.push_back(to_indices(list.begin() + static_cast<int64_t>(k), list.begin() + static_cast<int64_t>(k) + count));
          k += static_cast<size_t>(count);
        }
      }
      have_cells = true;
    } else if (keyword == "CELL_TYPES") {
      const int64_t n = in.next_int("the cell type count");
      if (static_cast<size_t>(n) != cells.size()) {
        in.fail("CELL_TYPES has " + std::to_string(n) + " entries, expected one per cell (" +
                std::to_string(cells.size()) + ")");
      }
      const auto types = values.read(n, "int", "cell type");
      for (int64_t c = 0; c < n; ++c) {
        const int64_t type = to_index(types[c]);
        if (type == 10) {
          if (cells[c].size() != 4) in.fail("tetra cell " + std::to_string(c) + " has " + std::to_string(cells[c].size()) + " points, expected 4");
          for (int64_t v : cells[c]) {
            if (v < 0 || v >= static_cast<int64_t>(mesh.points.size())) {
              in.fail("tetrahedron " + std::to_string(mesh.tets.size()) + " (cell " + std::to_string(c) + ") has vertex index " +
                      std::to_string(v) + ", expected 0.." + std::to_string(static_cast<int64_t>(mesh.points.size()) - 1));
            }
          }
          mesh.tets.push_back({static_cast<int32_t>(cells[c][0]), static_cast<int32_t>(cells[c][1]),
                               static_cast<int32_t>(cells[c][2]), static_cast<int32_t>(cells[c][3])});
        } else if (type != 1 && type != 3 && type != 5) {
          in.fail("cell " + std::to_string(c) + " has VTK type " + std::to_string(type) +
                  ", expected 10 (tetra); only linear tetrahedral meshes are supported");
        }
      }
      have_types = true;
    } else if (keyword == "FIELD") {
      in.next("the field name");
      const int64_t arrays = in.next_int("the field array count");
      for (int64_t a = 0; a < arrays; ++a) {
        in.next("an array name");
        // Each checked before their product, which could overflow.
        const int64_t components = in.checked_count(in.next_int("the component count"), 1, "components");
        const int64_t tuples = in.checked_count(in.next_int("the tuple count"), 1, "tuples");
        const std::string type(in.next("the array type"));
        values.read(components * tuples, type, "field value");
      }
    } else {
      in.fail("unexpected '" + keyword + "' before POINTS, CELLS and CELL_TYPES were read");
    }
  }
  if (!have_points || !have_cells || !have_types) {
    throw input_error(source, "missing POINTS, CELLS or CELL_TYPES section");
  }
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
}

}  // namespace organsim::mesh_io
