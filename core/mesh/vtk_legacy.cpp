// VTK legacy pieces shared by the unstructured grid and polydata readers.
#include "core/mesh/vtk_legacy.h"

#include <bit>
#include <cstdint>
#include <cmath>
#include <cstring>

namespace organsim::mesh_io {

namespace {

int type_size(std::string_view type) {
  if (type == "float") return 4;
  if (type == "double") return 8;
  if (type == "int" || type == "vtktypeint32") return 4;
  if (type == "vtktypeint64" || type == "long") return 8;
  return 0;
}

}  // namespace

std::vector<double> VtkValues::read(int64_t n, std::string_view type, const char* what) {
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
  const bool is_float = type == "float" || type == "double";
  for (int64_t i = 0; i < n; ++i, pos += static_cast<size_t>(size)) {
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + pos, static_cast<size_t>(size));
    if (std::endian::native == std::endian::little) {  // byte order of the file differs from the host's
      unsigned char swapped[8];
      for (int b = 0; b < size; ++b) swapped[b] = raw[size - 1 - b];
      std::memcpy(raw, swapped, sizeof raw);
    }
    if (size == 4 && is_float) { float v; std::memcpy(&v, raw, 4); values.push_back(v); }
    else if (size == 8 && is_float) { double v; std::memcpy(&v, raw, 8); values.push_back(v); }
    else if (size == 4) { int32_t v; std::memcpy(&v, raw, 4); values.push_back(v); }
    else { int64_t v; std::memcpy(&v, raw, 8); values.push_back(static_cast<double>(v)); }
  }
  in_.set_position(pos, in_.line());
  return values;
}

std::string read_vtk_legacy_header(TokenReader& in, bool& binary) {
  const std::string_view first = in.rest_of_line();
  if (first.find("vtk DataFile") == std::string_view::npos) {
    throw input_error(in.file(), "line 1: expected '# vtk DataFile Version ...' (VTK legacy format)");
  }
  in.rest_of_line();  // title
  const std::string_view encoding = in.next("ASCII or BINARY");
  if (encoding != "ASCII" && encoding != "BINARY") in.fail("expected ASCII or BINARY, got '" + std::string(encoding) + "'");
  binary = encoding == "BINARY";
  if (in.next("DATASET") != "DATASET") in.fail("expected 'DATASET UNSTRUCTURED_GRID' or 'DATASET POLYDATA'");
  return std::string(in.next("the dataset type"));
}

std::string not_a_triangle(size_t polygon, size_t points) {
  return "polygon " + std::to_string(polygon) + " has " + std::to_string(points) +
         " points; not a triangle surface (expected 3 per polygon: triangulate it first, e.g. with ParaView's or "
         "VTK's Triangulate filter)";
}

int64_t vtk_index(double v) { return v >= 0 && v < 9.0e15 && v == std::floor(v) ? static_cast<int64_t>(v) : -1; }

std::vector<Vec3> read_vtk_points(TokenReader& in, VtkValues& values) {
  // Checked before 3 * n, which could overflow.
  const int64_t n = in.checked_count(in.next_int("the point count"), 3, "points");
  const std::string type(in.next("the point data type"));
  const auto xyz = values.read(3 * n, type, "point coordinate");
  std::vector<Vec3> points;
  points.reserve(static_cast<size_t>(n));
  for (int64_t i = 0; i < n; ++i) points.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  return points;
}

std::vector<std::vector<int64_t>> read_vtk_cell_list(TokenReader& in, VtkValues& values, const std::string& keyword,
                                                     int64_t n) {
  const int64_t size = in.next_int("the cell list size");
  std::vector<std::vector<int64_t>> cells;
  const auto indices = [](std::vector<double>::const_iterator begin, std::vector<double>::const_iterator end) {
    std::vector<int64_t> ids;
    for (auto it = begin; it != end; ++it) ids.push_back(vtk_index(*it));
    return ids;
  };
  if (in.peek() == "OFFSETS") {  // VTK 5.1: n offsets (cells + 1) and `size` indices
    in.next("OFFSETS");
    const std::string otype(in.next("the offsets type"));
    const auto offsets = values.read(n, otype, "cell offset");
    if (in.next("CONNECTIVITY") != "CONNECTIVITY") in.fail("expected CONNECTIVITY");
    const std::string ctype(in.next("the connectivity type"));
    const auto ids = values.read(size, ctype, "cell connectivity index");
    for (int64_t c = 0; c + 1 < n; ++c) {
      const int64_t begin = vtk_index(offsets[c]), end = vtk_index(offsets[c + 1]);
      if (begin < 0 || end < begin || end > size) in.fail("cell " + std::to_string(c) + ": offsets out of range");
      cells.push_back(indices(ids.begin() + begin, ids.begin() + end));
    }
    return cells;
  }
  const auto list = values.read(size, "int", "cell list entry");
  if (n > size) in.fail(std::to_string(n) + " cells cannot fit in a list of " + std::to_string(size) + " entries");
  size_t k = 0;
  for (int64_t c = 0; c < n; ++c) {
    if (k >= list.size()) in.fail(keyword + " list is shorter than its " + std::to_string(n) + " cells");
    const int64_t count = vtk_index(list[k++]);
    if (count < 0 || k + static_cast<size_t>(count) > list.size()) {
      in.fail("cell " + std::to_string(c) + " has an invalid point count " + std::to_string(count));
    }
    cells.push_back(indices(list.begin() + static_cast<int64_t>(k), list.begin() + static_cast<int64_t>(k) + count));
    k += static_cast<size_t>(count);
  }
  return cells;
}

void skip_vtk_metadata(TokenReader& in) {
  in.rest_of_line();
  for (;;) {  // at the end of the file rest_of_line() is empty, i.e. blank
    const std::string_view line = in.rest_of_line();
    if (line.find_first_not_of(" \t") == std::string_view::npos) return;
  }
}

void skip_vtk_field(TokenReader& in, VtkValues& values) {
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
}

}  // namespace organsim::mesh_io
