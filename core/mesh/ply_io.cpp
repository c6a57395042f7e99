// Stanford PLY surfaces: ASCII and binary (little or big endian). Only vertex
// x, y, z and the face index list are used; other elements and properties are
// read past.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <ostream>
#include <vector>

#include "core/mesh/mesh_io_detail.h"
#include "core/util/format.h"

namespace organsim::mesh_io {

namespace {

enum class Format { Ascii, BinaryLittle, BinaryBig };

struct Property {
  std::string name;
  int size = 0;            // bytes of the scalar (or of the list items)
  char kind = 'f';         // 'i' signed, 'u' unsigned, 'f' float
  bool is_list = false;
  int count_size = 0;      // list: bytes of the count
  char count_kind = 'u';
};

struct Element {
  std::string name;
  int64_t count = 0;
  std::vector<Property> properties;
};

bool scalar_type(std::string_view name, int& size, char& kind) {
  static const struct { const char* name; int size; char kind; } types[] = {
      {"char", 1, 'i'},   {"int8", 1, 'i'},    {"uchar", 1, 'u'},  {"uint8", 1, 'u'},   {"short", 2, 'i'},
      {"int16", 2, 'i'},  {"ushort", 2, 'u'},  {"uint16", 2, 'u'}, {"int", 4, 'i'},     {"int32", 4, 'i'},
      {"uint", 4, 'u'},   {"uint32", 4, 'u'},  {"float", 4, 'f'},  {"float32", 4, 'f'}, {"double", 8, 'f'},
      {"float64", 8, 'f'}};
  for (const auto& t : types) {
    if (name == t.name) {
      size = t.size;
      kind = t.kind;
      return true;
    }
  }
  return false;
}

// Reads binary scalars with the file's byte order.
class BinaryCursor {
 public:
  BinaryCursor(std::string_view bytes, size_t pos, bool big, const std::string& source)
      : bytes_(bytes), pos_(pos), swap_(big != (std::endian::native == std::endian::big)), source_(source) {}
  double read(int size, char kind, const std::string& where) {
    if (pos_ + static_cast<size_t>(size) > bytes_.size()) {
      throw input_error(source_, where + ": file ends early (truncated binary PLY)");
    }
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + pos_, static_cast<size_t>(size));
    pos_ += static_cast<size_t>(size);
    if (swap_) {  // byte order of the file differs from the host's
      unsigned char swapped[8] = {};  // zeroed: gcc 12 without -march=native warns otherwise
      for (int b = 0; b < size; ++b) swapped[b] = raw[size - 1 - b];
      std::memcpy(raw, swapped, static_cast<size_t>(size));
    }
    switch (size * 4 + (kind == 'f' ? 2 : kind == 'i' ? 1 : 0)) {
      case 4: return *raw;
      case 5: { int8_t v; std::memcpy(&v, raw, 1); return v; }
      case 8: { uint16_t v; std::memcpy(&v, raw, 2); return v; }
      case 9: { int16_t v; std::memcpy(&v, raw, 2); return v; }
      case 16: { uint32_t v; std::memcpy(&v, raw, 4); return v; }
      case 17: { int32_t v; std::memcpy(&v, raw, 4); return v; }
      case 18: { float v; std::memcpy(&v, raw, 4); return v; }
      case 34: { double v; std::memcpy(&v, raw, 8); return v; }
      default: throw input_error(source_, where + ": unsupported PLY scalar type");
    }
  }

 private:
  std::string_view bytes_;
  size_t pos_;
  bool swap_;
  const std::string& source_;
};

}  // namespace

TriangleMesh read_ply(std::string_view bytes, const std::string& source) {
  const size_t header_end = bytes.find("end_header");
  if (bytes.substr(0, 3) != "ply" || header_end == std::string_view::npos) {
    throw input_error(source, "not a PLY file (expected 'ply' on the first line and an 'end_header' line)");
  }
  TokenReader header(bytes.substr(0, header_end), source, 0);
  header.next("'ply'");
  Format format = Format::Ascii;
  std::vector<Element> elements;
  while (!header.at_end()) {
    const std::string_view word = header.next("a header keyword");
    if (word == "format") {
      const std::string_view f = header.next("the PLY format");
      if (f == "ascii") format = Format::Ascii;
      else if (f == "binary_little_endian") format = Format::BinaryLittle;
      else if (f == "binary_big_endian") format = Format::BinaryBig;
      else header.fail("unknown PLY format '" + std::string(f) + "'");
      header.skip_line();
    } else if (word == "element") {
      Element e;
      e.name = header.next("an element name");
      e.count = header.next_int("the element count");
      if (e.count < 0 || e.count > static_cast<int64_t>(bytes.size())) {
        header.fail("element count " + std::to_string(e.count) + " is negative or larger than the file");
      }
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) header.fail("'property' before any 'element'");
      Property p;
      std::string_view type = header.next("a property type");
      if (type == "list") {
        p.is_list = true;
        const std::string_view count_type = header.next("the list count type");
        if (!scalar_type(count_type, p.count_size, p.count_kind)) header.fail("unknown PLY type '" + std::string(count_type) + "'");
        type = header.next("the list item type");
      }
      if (!scalar_type(type, p.size, p.kind)) header.fail("unknown PLY type '" + std::string(type) + "'");
      p.name = header.next("a property name");
      elements.back().properties.push_back(p);
    } else {
      header.skip_line();  // comment, obj_info
    }
  }
  size_t body = header_end + std::string_view("end_header").size();
  while (body < bytes.size() && bytes[body] != '\n') ++body;
  if (body < bytes.size()) ++body;  // past the newline; a file may end right after end_header

  TriangleMesh mesh;
  // Reads one element instance, calling `value(property_index, item, v)` for each number.
  const auto read_elements = [&](auto&& read_scalar, auto&& read_count) {
    for (const Element& e : elements) {
      const bool is_vertex = e.name == "vertex";
      const bool is_face = e.name == "face";
      int xyz[3] = {-1, -1, -1};
      int index_list = -1;
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const std::string& n = e.properties[k].name;
        if (n == "x") xyz[0] = static_cast<int>(k);
        if (n == "y") xyz[1] = static_cast<int>(k);
        if (n == "z") xyz[2] = static_cast<int>(k);
        if (e.properties[k].is_list && (n == "vertex_indices" || n == "vertex_index")) index_list = static_cast<int>(k);
      }
      if (is_vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)) {
        throw input_error(source, "PLY element 'vertex' lacks an x, y or z property");
      }
      if (is_face && index_list < 0) {
        throw input_error(source, "PLY element 'face' lacks a 'vertex_indices' list property");
      }
      for (int64_t i = 0; i < e.count; ++i) {
        const std::string where = e.name + " " + std::to_string(i);
        Vec3 p = Vec3::Zero();
        std::vector<int64_t> corners;
        for (size_t k = 0; k < e.properties.size(); ++k) {
          const Property& prop = e.properties[k];
          if (prop.is_list) {
            // The count's type is the file's choice (even float): check it is
            // a whole number before it becomes one.
            const double length = read_count(prop, where);
            if (!(length >= 0 && length <= 2147483647.0 && length == std::floor(length))) {
              throw input_error(source, where + ": list length " + format_number(length) + ", expected a count >= 0");
            }
            const auto n = static_cast<int64_t>(length);
            for (int64_t j = 0; j < n; ++j) {
              const double v = read_scalar(prop, where);
              if (static_cast<int>(k) == index_list) {
                if (!(v >= 0 && v < 2147483647.0)) throw input_error(source, where + ": vertex index " + std::to_string(v) + " out of range");
                corners.push_back(static_cast<int64_t>(v));
              }
            }
          } else {
            const double v = read_scalar(prop, where);
            for (int c = 0; c < 3; ++c) {
              if (static_cast<int>(k) == xyz[c]) p[c] = v;
            }
          }
        }
        if (is_vertex) mesh.points.push_back(p);
        if (is_face) {
          if (corners.size() != 3) {
            throw input_error(source, where + " has " + std::to_string(corners.size()) +
                                          " vertices; not a triangle mesh (expected 3 per face: triangulate the surface first)");
          }
          mesh.faces.push_back({static_cast<int32_t>(corners[0]), static_cast<int32_t>(corners[1]),
                                static_cast<int32_t>(corners[2])});
        }
      }
    }
  };

  if (format == Format::Ascii) {
    TokenReader in(bytes.substr(body), source, 0);
    const auto scalar = [&](const Property&, const std::string& where) {
      return in.next_double((where + " value").c_str());
    };
    const auto count = [&](const Property&, const std::string& where) {
      return static_cast<double>(in.next_int((where + " list length").c_str()));
    };
    read_elements(scalar, count);
  } else {
    BinaryCursor in(bytes, body, format == Format::BinaryBig, source);
    const auto scalar = [&](const Property& p, const std::string& where) { return in.read(p.size, p.kind, where); };
    const auto count = [&](const Property& p, const std::string& where) {
      return in.read(p.count_size, p.count_kind, where);
    };
    read_elements(scalar, count);
  }
  check_surface_indices(mesh, source);
  return mesh;
}

void write_ply_ascii(std::ostream& out, const TriangleMesh& mesh) {
  out << "ply\nformat ascii 1.0\ncomment organsim surface, metres\n";
  out << "element vertex " << mesh.points.size() << "\nproperty double x\nproperty double y\nproperty double z\n";
  out << "element face " << mesh.faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Vec3& p : mesh.points) {
    write_point(out, p);
    out << '\n';
  }
  for (const Tri& f : mesh.faces) out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
}

}  // namespace organsim::mesh_io
