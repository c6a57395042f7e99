// VTK XML surfaces (.vtp, PolyData) and tet meshes (.vtu, UnstructuredGrid).
// Data arrays may be ascii, inline binary (base64, with a UInt32 or UInt64
// byte-count header) or appended raw; either byte order. Compressed files and
// appended base64 are refused with a message that says how to save them.
// Every size comes from the data actually present, never from a declared
// count, so a corrupt header cannot make us allocate more than the file holds.
#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <vector>

#include "core/mesh/vtk_legacy.h"  // vtk_index
#include "core/util/format.h"

namespace organsim::mesh_io {

namespace {

using Attributes = std::map<std::string, std::string, std::less<>>;

struct XmlArray {
  std::string parent;  // Points, Cells, Polys, Strips, Verts, Lines, PointData, ...
  Attributes attrs;
  size_t begin = 0, end = 0;  // content range in the file
};

struct XmlDocument {
  Attributes file;              // <VTKFile ...>
  std::string dataset;          // "PolyData" or "UnstructuredGrid"
  std::vector<Attributes> pieces;
  std::vector<XmlArray> arrays;
  std::optional<size_t> appended;  // first byte after '_' in <AppendedData>
  std::string appended_encoding;
};

class XmlScanner {
 public:
  XmlScanner(std::string_view text, const std::string& source) : text_(text), source_(source) {}

  [[noreturn]] void fail(size_t pos, const std::string& message) const {
    int line = 1;
    for (size_t i = 0; i < pos && i < text_.size(); ++i) line += text_[i] == '\n';
    throw input_error(source_, "line " + std::to_string(line) + ": " + message);
  }

  XmlDocument scan() {
    XmlDocument doc;
    std::vector<std::string> open;
    size_t pos = 0;
    while ((pos = text_.find('<', pos)) != std::string_view::npos) {
      if (text_.compare(pos, 4, "<!--") == 0) { pos = skip_past(pos, "-->"); continue; }
      if (text_.compare(pos, 2, "<?") == 0) { pos = skip_past(pos, "?>"); continue; }
      if (text_.compare(pos, 2, "<!") == 0) { pos = skip_past(pos, ">"); continue; }
      const size_t tag_start = pos;
      const bool closing = text_.compare(pos, 2, "</") == 0;
      pos += closing ? 2 : 1;
      const std::string name = read_name(pos);
      if (closing) {
        if (open.empty() || open.back() != name) fail(tag_start, "unexpected </" + name + ">");
        open.pop_back();
        pos = skip_past(pos, ">");
        continue;
      }
      Attributes attrs;
      bool self_closing = false;
      for (;;) {
        skip_space(pos);
        if (pos >= text_.size()) fail(tag_start, "file ends inside <" + name + ">");
        if (text_[pos] == '>') { ++pos; break; }
        if (text_.compare(pos, 2, "/>") == 0) { pos += 2; self_closing = true; break; }
        const std::string key = read_name(pos);
        skip_space(pos);
        if (pos >= text_.size() || text_[pos] != '=') fail(pos, "expected '=' after attribute " + key + " of <" + name + ">");
        ++pos;
        skip_space(pos);
        if (pos >= text_.size() || (text_[pos] != '"' && text_[pos] != '\'')) fail(pos, "expected a quoted value for " + key);
        const char quote = text_[pos++];
        const size_t close = text_.find(quote, pos);
        if (close == std::string_view::npos) fail(pos, "unterminated value of " + key);
        attrs[key] = std::string(text_.substr(pos, close - pos));
        pos = close + 1;
      }
      if (open.empty() && name != "VTKFile") fail(tag_start, "expected <VTKFile> (VTK XML format), got <" + name + ">");
      if (name == "VTKFile") {
        doc.file = attrs;
        doc.dataset = attrs.count("type") ? attrs["type"] : "";
      } else if (name == "Piece") {
        doc.pieces.push_back(attrs);
      } else if (name == "DataArray") {
        XmlArray a;
        a.parent = open.empty() ? "" : open.back();
        a.attrs = attrs;
        a.begin = pos;
        a.end = self_closing ? pos : std::min(text_.find('<', pos), text_.size());
        doc.arrays.push_back(std::move(a));
      } else if (name == "AppendedData") {
        // Raw bytes follow: they may contain '<', so scanning stops here.
        const size_t underscore = text_.find('_', pos);
        if (underscore == std::string_view::npos) fail(pos, "<AppendedData> without the '_' that starts the data");
        doc.appended = underscore + 1;
        doc.appended_encoding = attrs.count("encoding") ? attrs["encoding"] : "";
        return doc;
      }
      if (!self_closing) open.push_back(name);
    }
    if (doc.file.empty()) fail(0, "no <VTKFile> element (VTK XML format expected)");
    return doc;
  }

 private:
  size_t skip_past(size_t pos, std::string_view end) const {
    const size_t at = text_.find(end, pos);
    if (at == std::string_view::npos) fail(pos, "unterminated markup, expected '" + std::string(end) + "'");
    return at + end.size();
  }
  void skip_space(size_t& pos) const {
    while (pos < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos]))) ++pos;
  }
  std::string read_name(size_t& pos) const {
    const size_t start = pos;
    while (pos < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[pos])) || text_[pos] == '_' ||
                                  text_[pos] == ':' || text_[pos] == '-' || text_[pos] == '.')) {
      ++pos;
    }
    if (pos == start) fail(start, "expected a name in the markup");
    return std::string(text_.substr(start, pos - start));
  }

  std::string_view text_;
  const std::string& source_;
};

// Decodes base64, skipping whitespace; a padded quantum may be followed by
// more data (VTK encodes a header and its data as separate runs).
bool decode_base64(std::string_view text, std::string& out) {
  const auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  out.clear();
  out.reserve(text.size() / 4 * 3);
  int quantum[4];
  int n = 0, pad = 0;
  for (char c : text) {
    if (std::isspace(static_cast<unsigned char>(c))) continue;
    if (c == '=') {
      if (n < 2) return false;
      quantum[n++] = 0;
      ++pad;
    } else {
      const int v = value(c);
      if (v < 0 || pad > 0) return false;
      quantum[n++] = v;
    }
    if (n == 4) {
      const uint32_t bits = (uint32_t(quantum[0]) << 18) | (uint32_t(quantum[1]) << 12) | (uint32_t(quantum[2]) << 6) | uint32_t(quantum[3]);
      out.push_back(static_cast<char>(bits >> 16));
      if (pad < 2) out.push_back(static_cast<char>((bits >> 8) & 0xff));
      if (pad < 1) out.push_back(static_cast<char>(bits & 0xff));
      n = 0;
      pad = 0;
    }
  }
  return n == 0;
}

struct ScalarType {
  int size = 0;
  bool is_float = false, is_signed = false;
};

ScalarType scalar_type(std::string_view name) {
  if (name == "Float32") return {4, true, true};
  if (name == "Float64") return {8, true, true};
  if (name == "Int8") return {1, false, true};
  if (name == "UInt8") return {1, false, false};
  if (name == "Int16") return {2, false, true};
  if (name == "UInt16") return {2, false, false};
  if (name == "Int32") return {4, false, true};
  if (name == "UInt32") return {4, false, false};
  if (name == "Int64") return {8, false, true};
  if (name == "UInt64") return {8, false, false};
  return {};
}

// One value of `type` from raw bytes in the file's byte order.
double load_value(const char* p, const ScalarType& type, bool swap) {
  unsigned char raw[8] = {};
  const int n = std::clamp(type.size, 1, 8);
  for (int b = 0; b < n; ++b) raw[b] = static_cast<unsigned char>(p[swap ? n - 1 - b : b]);
  if (type.is_float) {
    if (type.size == 4) { float v; std::memcpy(&v, raw, 4); return v; }
    double v; std::memcpy(&v, raw, 8); return v;
  }
  uint64_t u = 0;
  std::memcpy(&u, raw, static_cast<size_t>(type.size));  // little-endian host: low bytes first
  if (type.is_signed && type.size < 8 && (u >> (8 * type.size - 1)) & 1) u |= ~uint64_t(0) << (8 * type.size);
  return type.is_signed ? static_cast<double>(static_cast<int64_t>(u)) : static_cast<double>(u);
}

class VtkXmlReader {
 public:
  VtkXmlReader(std::string_view bytes, const std::string& source, const char* expected_type)
      : bytes_(bytes), source_(source), scanner_(bytes, source) {
    if (std::endian::native != std::endian::little) throw input_error(source, "VTK XML reading needs a little-endian host");
    doc_ = scanner_.scan();
    if (doc_.dataset != expected_type) {
      fail("VTKFile type \"" + doc_.dataset + "\": expected \"" + expected_type + "\"");
    }
    if (doc_.file.count("compressor")) {
      fail("compressed data (" + doc_.file["compressor"] +
                  ") is not supported; save the file uncompressed (ParaView: Save Data, Compressor Type None)");
    }
    const std::string order = doc_.file.count("byte_order") ? doc_.file["byte_order"] : "LittleEndian";
    if (order != "LittleEndian" && order != "BigEndian") fail("byte_order \"" + order + "\": expected LittleEndian or BigEndian");
    swap_ = order == "BigEndian";
    const std::string header = doc_.file.count("header_type") ? doc_.file["header_type"] : "UInt32";
    if (header != "UInt32" && header != "UInt64") fail("header_type \"" + header + "\": expected UInt32 or UInt64");
    header_ = scalar_type(header);
    if (doc_.pieces.size() != 1) {
      fail(std::to_string(doc_.pieces.size()) + " <Piece> elements, expected exactly 1");
    }
  }

  [[noreturn]] void fail(size_t pos, const std::string& message) const { scanner_.fail(pos, message); }
  // For faults of an element rather than of a place in the text.
  [[noreturn]] void fail(const std::string& message) const { throw input_error(source_, message); }

  // The piece's declared count `key`, checked to be a non-negative integer.
  int64_t piece_count(const char* key) const {
    const auto it = doc_.pieces[0].find(key);
    if (it == doc_.pieces[0].end()) return 0;
    int64_t n = 0;
    if (!parse_int(it->second, n) || n < 0) fail(std::string("Piece ") + key + "=\"" + it->second + "\": expected a count >= 0");
    return n;
  }

  // The array of `parent` named `name` (the first one when name is empty).
  const XmlArray* find(std::string_view parent, std::string_view name) const {
    for (const XmlArray& a : doc_.arrays) {
      if (a.parent != parent) continue;
      const auto it = a.attrs.find("Name");
      if (name.empty() || (it != a.attrs.end() && it->second == name)) return &a;
    }
    return nullptr;
  }

  // The values of `parent`/`name`, which must be exactly `count` x `components`.
  std::vector<double> values(std::string_view parent, std::string_view name, int64_t count, int components) {
    const XmlArray* a = find(parent, name);
    std::string what = "<";
    what.append(parent).append("> DataArray");
    if (!name.empty()) what.append(" \"").append(name).append("\"");
    if (!a) fail("missing " + what);
    const auto attr = [&](const char* key, const char* fallback) {
      const auto it = a->attrs.find(key);
      return it == a->attrs.end() ? std::string(fallback) : it->second;
    };
    const ScalarType type = scalar_type(attr("type", ""));
    if (type.size == 0) fail(a->begin, what + ": type \"" + attr("type", "") + "\" is not a VTK scalar type");
    int64_t nc = 1;
    if (!parse_int(attr("NumberOfComponents", "1"), nc) || nc != components) {
      fail(a->begin, what + ": NumberOfComponents " + attr("NumberOfComponents", "1") + ", expected " + std::to_string(components));
    }
    if (count > INT64_MAX / 4) fail(a->begin, what + ": count " + std::to_string(count) + " is too large");
    const std::string format = attr("format", "ascii");
    std::vector<double> out;
    if (format == "ascii") {
      TokenReader in(bytes_.substr(0, a->end), source_, 0);
      size_t line = 1;
      for (size_t i = 0; i < a->begin; ++i) line += bytes_[i] == '\n';
      in.set_position(a->begin, static_cast<int>(line));
      while (!in.at_end()) out.push_back(in.next_double("a value"));
    } else if (format == "binary") {
      std::string decoded;
      if (!decode_base64(bytes_.substr(a->begin, a->end - a->begin), decoded)) fail(a->begin, what + ": invalid base64 data");
      unpack(decoded, type, out, *a, what);
    } else if (format == "appended") {
      if (!doc_.appended) fail(a->begin, what + ": format appended but the file has no <AppendedData>");
      if (doc_.appended_encoding != "raw") {
        fail(a->begin, what + ": appended data encoded \"" + doc_.appended_encoding +
                           "\" is not supported; save with raw appended data or inline binary");
      }
      int64_t offset = 0;
      if (!parse_int(attr("offset", ""), offset) || offset < 0) fail(a->begin, what + ": expected an offset >= 0");
      const size_t start = *doc_.appended + static_cast<size_t>(offset);
      if (start > bytes_.size()) fail(a->begin, what + ": offset " + std::to_string(offset) + " lies past the end of the file");
      unpack(bytes_.substr(start), type, out, *a, what);
    } else {
      fail(a->begin, what + ": format \"" + format + "\", expected ascii, binary or appended");
    }
    const int64_t expected = count * components;
    if (static_cast<int64_t>(out.size()) != expected) {
      fail(a->begin, what + " holds " + std::to_string(out.size()) + " values, expected " + std::to_string(expected) +
                         " (" + std::to_string(count) + " x " + std::to_string(components) + ")");
    }
    return out;
  }

  std::vector<Vec3> points() {
    const int64_t n = piece_count("NumberOfPoints");
    const auto xyz = values("Points", "", n, 3);
    std::vector<Vec3> p;
    p.reserve(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) p.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    return p;
  }

  // Cells of `parent` (Cells, Polys, Strips) from connectivity and offsets.
  std::vector<std::vector<int64_t>> cells(std::string_view parent, int64_t n) {
    if (n == 0) return {};
    const auto offsets = values(parent, "offsets", n, 1);
    const XmlArray* c = find(parent, "connectivity");
    const int64_t size = n == 0 ? 0 : vtk_index(offsets.back());
    if (size < 0) fail(c ? c->begin : 0, "<" + std::string(parent) + "> offsets: last offset is not a valid count");
    const auto ids = values(parent, "connectivity", size, 1);
    std::vector<std::vector<int64_t>> cells;
    int64_t begin = 0;
    for (int64_t k = 0; k < n; ++k) {
      const int64_t end = vtk_index(offsets[k]);
      if (end < begin || end > size) fail("<" + std::string(parent) + "> cell " + std::to_string(k) + ": offsets not increasing");
      std::vector<int64_t> cell;
      for (int64_t j = begin; j < end; ++j) cell.push_back(vtk_index(ids[j]));
      cells.push_back(std::move(cell));
      begin = end;
    }
    return cells;
  }

 private:
  void unpack(std::string_view data, const ScalarType& type, std::vector<double>& out, const XmlArray& a,
              const std::string& what) {
    const size_t hsize = static_cast<size_t>(header_.size);
    if (data.size() < hsize) fail(a.begin, what + ": data shorter than its byte-count header");
    const double declared = load_value(data.data(), header_, swap_);
    // Compared as a double: a UInt64 header can hold more than size_t or
    // uint64_t round-trips through a double (2^64 - 1 becomes 2^64).
    if (!(declared >= 0) || declared > static_cast<double>(data.size() - hsize)) {
      fail(a.begin, what + ": header declares " + format_number(declared) + " bytes, only " +
                        std::to_string(data.size() - hsize) + " present");
    }
    const auto nbytes = static_cast<size_t>(declared);
    if (nbytes % static_cast<size_t>(type.size) != 0) fail(a.begin, what + ": byte count is not a whole number of values");
    out.reserve(nbytes / static_cast<size_t>(type.size));
    for (size_t p = hsize; p < hsize + nbytes; p += static_cast<size_t>(type.size)) {
      out.push_back(load_value(data.data() + p, type, swap_));
    }
  }

  std::string_view bytes_;
  std::string source_;
  XmlScanner scanner_;
  XmlDocument doc_;
  bool swap_ = false;
  ScalarType header_;
};

}  // namespace

TriangleMesh read_vtp(std::string_view bytes, const std::string& source) {
  VtkXmlReader in(bytes, source, "PolyData");
  TriangleMesh mesh;
  mesh.points = in.points();
  const auto npoint = static_cast<int64_t>(mesh.points.size());
  const auto add = [&](int64_t a, int64_t b, int64_t c, const std::string& what) {
    for (int64_t v : {a, b, c}) {
      if (v < 0 || v >= npoint) {
        in.fail(what + " refers to point " + std::to_string(v) + ", expected an index in [0, " + std::to_string(npoint) + ")");
      }
    }
    mesh.faces.push_back({static_cast<int32_t>(a), static_cast<int32_t>(b), static_cast<int32_t>(c)});
  };
  const auto polys = in.cells("Polys", in.piece_count("NumberOfPolys"));
  for (size_t k = 0; k < polys.size(); ++k) {
    const std::string what = "polygon " + std::to_string(k);
    if (polys[k].size() != 3) in.fail(not_a_triangle(k, polys[k].size()));
    add(polys[k][0], polys[k][1], polys[k][2], what);
  }
  const auto strips = in.cells("Strips", in.piece_count("NumberOfStrips"));
  for (size_t k = 0; k < strips.size(); ++k) {
    const auto& s = strips[k];
    // Every other triangle of a strip is reversed to keep its orientation.
    for (size_t j = 0; j + 2 < s.size(); ++j) {
      if (j % 2 == 0) add(s[j], s[j + 1], s[j + 2], "triangle strip " + std::to_string(k));
      else add(s[j + 1], s[j], s[j + 2], "triangle strip " + std::to_string(k));
    }
  }
  if (mesh.faces.empty()) throw input_error(source, "no polygons or triangle strips: the file holds no surface");
  return mesh;
}

TetMesh read_vtu(std::string_view bytes, const std::string& source) {
  VtkXmlReader in(bytes, source, "UnstructuredGrid");
  TetMesh mesh;
  mesh.points = in.points();
  const int64_t ncell = in.piece_count("NumberOfCells");
  const auto cells = in.cells("Cells", ncell);
  const auto types = in.values("Cells", "types", ncell, 1);
  const auto npoint = static_cast<int64_t>(mesh.points.size());
  std::vector<int64_t> tet_cells;  // the cell each tet is
  for (int64_t c = 0; c < ncell; ++c) {
    const int64_t type = vtk_index(types[c]);
    if (type == 1 || type == 3 || type == 5) continue;  // vertices, lines, triangles: read past
    if (type != 10) {
      in.fail("cell " + std::to_string(c) + " has VTK type " + std::to_string(type) +
                     ", expected 10 (tetra); only linear tetrahedral meshes are supported");
    }
    if (cells[c].size() != 4) in.fail("tetra cell " + std::to_string(c) + " has " + std::to_string(cells[c].size()) + " points, expected 4");
    Tet tet{};
    for (int k = 0; k < 4; ++k) {
      if (cells[c][k] < 0 || cells[c][k] >= npoint) {
        in.fail("tetrahedron " + std::to_string(mesh.tets.size()) + " (cell " + std::to_string(c) + ") has vertex index " +
                       std::to_string(cells[c][k]) + ", expected 0.." + std::to_string(npoint - 1));
      }
      tet[k] = static_cast<int32_t>(cells[c][k]);
    }
    mesh.tets.push_back(tet);
    tet_cells.push_back(c);
  }
  // The cell array `label` is each tet's label.
  if (in.find("CellData", "label") != nullptr) {
    const auto labels = in.values("CellData", "label", ncell, 1);
    for (int64_t c : tet_cells) {
      int32_t label = 0;
      if (!label_from_value(labels[static_cast<size_t>(c)], label)) {
        in.fail("cell " + std::to_string(c) + " has label " + format_number(labels[static_cast<size_t>(c)]) +
                ", expected a 32-bit integer");
      }
      mesh.labels.push_back(label);
    }
  }
  return mesh;
}

}  // namespace organsim::mesh_io
