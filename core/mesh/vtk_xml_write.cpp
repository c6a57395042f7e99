// VTK XML writers: one <Piece>, arrays as inline base64 (header + data in one
// run, as VTK writes uncompressed binary).
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <ostream>

#include "core/mesh/vtk_xml.h"

namespace organsim {

namespace {

void write_base64(std::ostream& out, const std::string& bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string text;
  text.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    uint32_t bits = 0;
    for (size_t k = 0; k < 3; ++k) bits = (bits << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (size_t k = 0; k < 4; ++k) text.push_back(k <= n ? kDigits[(bits >> (18 - 6 * k)) & 63] : '=');
  }
  out << text;
}

template <class T>
void append(std::string& bytes, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  bytes.append(raw, sizeof(T));
}

// <DataArray> of `values` converted to T, base64 with its byte count first.
template <class T>
void write_array(std::ostream& out, const char* type, const std::string& name, int components,
                 const std::vector<T>& values) {
  out << "<DataArray type=\"" << type << "\"";
  if (!name.empty()) out << " Name=\"" << name << "\"";
  out << " NumberOfComponents=\"" << components << "\" format=\"binary\">\n";
  std::string bytes;
  bytes.reserve(8 + values.size() * sizeof(T));
  append<uint64_t>(bytes, values.size() * sizeof(T));
  for (T v : values) append<T>(bytes, v);
  write_base64(out, bytes);
  out << "\n</DataArray>\n";
}

void write_attributes(std::ostream& out, const char* element, const std::vector<VtkArray>& arrays) {
  out << "<" << element << ">\n";
  for (const VtkArray& a : arrays) {
    if (a.as_uint8) {
      std::vector<uint8_t> v(a.values.begin(), a.values.end());
      write_array(out, "UInt8", a.name, a.components, v);
    } else if (a.as_int32) {
      std::vector<int32_t> v(a.values.begin(), a.values.end());
      write_array(out, "Int32", a.name, a.components, v);
    } else {
      write_array(out, "Float64", a.name, a.components, a.values);
    }
  }
  out << "</" << element << ">\n";
}

void write_header(std::ostream& out, const char* type) {
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"" << type << "\" version=\"1.0\" byte_order=\""
      << (std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian")
      << "\" header_type=\"UInt64\">\n<" << type << ">\n";
}

void write_points(std::ostream& out, const std::vector<Vec3>& points) {
  std::vector<double> xyz;
  xyz.reserve(3 * points.size());
  for (const Vec3& p : points) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
  out << "<Points>\n";
  write_array(out, "Float64", "Points", 3, xyz);
  out << "</Points>\n";
}

// connectivity + offsets of cells with `corners` points each.
template <class Cell>
void write_cells(std::ostream& out, const std::vector<Cell>& cells, int corners) {
  std::vector<int64_t> connectivity, offsets;
  connectivity.reserve(cells.size() * static_cast<size_t>(corners));
  offsets.reserve(cells.size());
  for (const Cell& c : cells) {
    for (int k = 0; k < corners; ++k) connectivity.push_back(c[k]);
    offsets.push_back(static_cast<int64_t>(connectivity.size()));
  }
  write_array(out, "Int64", "connectivity", 1, connectivity);
  write_array(out, "Int64", "offsets", 1, offsets);
}

}  // namespace

VtkArray label_cell_array(const std::vector<int32_t>& labels) {
  VtkArray a;
  a.name = "label";
  a.values.assign(labels.begin(), labels.end());
  a.as_int32 = true;
  return a;
}

void write_vtu(std::ostream& out, const std::vector<Vec3>& points, const std::vector<Tet>& tets,
               const VtkAttributes& attributes) {
  write_header(out, "UnstructuredGrid");
  out << "<Piece NumberOfPoints=\"" << points.size() << "\" NumberOfCells=\"" << tets.size() << "\">\n";
  write_attributes(out, "PointData", attributes.point_data);
  write_attributes(out, "CellData", attributes.cell_data);
  write_points(out, points);
  out << "<Cells>\n";
  write_cells(out, tets, 4);
  write_array(out, "UInt8", "types", 1, std::vector<uint8_t>(tets.size(), 10));  // VTK_TETRA
  out << "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}

void write_vtp(std::ostream& out, const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
               const VtkAttributes& attributes) {
  write_header(out, "PolyData");
  out << "<Piece NumberOfPoints=\"" << points.size() << "\" NumberOfPolys=\"" << triangles.size() << "\">\n";
  write_attributes(out, "PointData", attributes.point_data);
  write_attributes(out, "CellData", attributes.cell_data);
  write_points(out, points);
  out << "<Polys>\n";
  write_cells(out, triangles, 3);
  out << "</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n";
}

void write_pvd(std::ostream& out, const std::vector<std::pair<double, std::string>>& steps) {
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\">\n<Collection>\n";
  for (const auto& [t, file] : steps) {
    char buffer[32];
    const auto end = std::to_chars(buffer, buffer + sizeof buffer, t).ptr;
    out << "<DataSet timestep=\"" << std::string(buffer, end) << "\" part=\"0\" file=\"" << file << "\"/>\n";
  }
  out << "</Collection>\n</VTKFile>\n";
}

}  // namespace organsim
