// OFF and Wavefront OBJ surfaces (text formats).
#include <ostream>
#include <sstream>
#include <vector>

#include "core/mesh/mesh_io_detail.h"

namespace organsim::mesh_io {

namespace {

[[noreturn]] void not_triangle(const std::string& source, int line, size_t face, size_t corners) {
  throw input_error(source, "line " + std::to_string(line) + ": face " + std::to_string(face) + " has " +
                                std::to_string(corners) +
                                " vertices; not a triangle mesh (expected 3 per face: triangulate the surface first)");
}

std::vector<std::string_view> split_whitespace(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    size_t j = i;
    while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
    if (j > i) tokens.push_back(line.substr(i, j - i));
    i = j;
  }
  return tokens;
}

}  // namespace

TriangleMesh read_off(std::string_view text, const std::string& source) {
  TokenReader in(text, source);
  // Header: OFF (or COFF, NOFF, ... whose extra per-vertex data we skip),
  // optionally followed on the same line by the counts.
  const std::string header(in.next("the OFF header"));
  if (header.size() < 3 || header.compare(header.size() - 3, 3, "OFF") != 0) {
    in.fail("expected the header 'OFF', got '" + header + "'");
  }
  if (in.peek() == "BINARY") in.fail("binary OFF is not supported; save the surface as ASCII OFF");
  const int64_t nv = in.checked_count(in.next_int("the vertex count"), 6, "vertices");
  const int64_t nf = in.next_int("the face count");
  in.next_int("the edge count");
  in.checked_count(nf, 8, "faces");
  in.skip_line();
  TriangleMesh mesh;
  mesh.points.reserve(static_cast<size_t>(nv));
  for (int64_t i = 0; i < nv; ++i) {
    const double x = in.next_double("a vertex x coordinate");
    const double y = in.next_double("a vertex y coordinate");
    const double z = in.next_double("a vertex z coordinate");
    mesh.points.emplace_back(x, y, z);
    in.skip_line();  // colours or normals after the position
  }
  mesh.faces.reserve(static_cast<size_t>(nf));
  for (int64_t f = 0; f < nf; ++f) {
    const int64_t corners = in.next_int("a face's vertex count");
    const int line = in.line();
    if (corners != 3) not_triangle(source, line, static_cast<size_t>(f), static_cast<size_t>(corners));
    Tri tri{};
    for (int k = 0; k < 3; ++k) {
      const int64_t v = in.next_int("a face vertex index");
      if (v < 0 || v >= nv) {
        in.fail("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + ", expected an index in [0, " +
                std::to_string(nv) + ")");
      }
      tri[k] = static_cast<int32_t>(v);
    }
    mesh.faces.push_back(tri);
    in.skip_line();  // colour after the indices
  }
  return mesh;
}

TriangleMesh read_obj(std::string_view text, const std::string& source) {
  TriangleMesh mesh;
  TokenReader in(text, source, 0);
  while (in.position() < text.size()) {
    const int line_number = in.line();
    std::string_view line = in.rest_of_line();
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    const auto tokens = split_whitespace(line);
    if (tokens.empty()) continue;
    const auto fail = [&](const std::string& message) {
      throw input_error(source, "line " + std::to_string(line_number) + ": " + message);
    };
    if (tokens[0] == "v") {
      if (tokens.size() < 4) fail("expected 'v x y z'");
      double c[3];
      for (int k = 0; k < 3; ++k) {
        if (!parse_double(tokens[1 + k], c[k])) fail("expected a number, got '" + std::string(tokens[1 + k]) + "'");
      }
      mesh.points.emplace_back(c[0], c[1], c[2]);
    } else if (tokens[0] == "f") {
      const size_t corners = tokens.size() - 1;
      if (corners != 3) not_triangle(source, line_number, mesh.faces.size(), corners);
      Tri tri{};
      const auto nv = static_cast<int64_t>(mesh.points.size());
      for (int k = 0; k < 3; ++k) {
        // "v", "v/vt", "v//vn" or "v/vt/vn": only the position index matters.
        std::string_view ref = tokens[1 + k];
        ref = ref.substr(0, ref.find('/'));
        int64_t v = 0;
        if (!parse_int(ref, v) || v == 0) fail("expected a vertex index, got '" + std::string(tokens[1 + k]) + "'");
        const int64_t index = v > 0 ? v - 1 : nv + v;  // negative: relative to the vertices read so far
        if (index < 0 || index >= nv) {
          fail("face refers to vertex " + std::to_string(v) + ", but only " + std::to_string(nv) +
               " vertices precede it (OBJ indices start at 1)");
        }
        tri[k] = static_cast<int32_t>(index);
      }
      mesh.faces.push_back(tri);
    }
    // vt, vn, g, o, s, usemtl, mtllib (even of a missing file), l: not geometry we use.
  }
  return mesh;
}

void write_off(std::ostream& out, const TriangleMesh& mesh) {
  out << "OFF\n" << mesh.points.size() << ' ' << mesh.faces.size() << " 0\n";
  for (const Vec3& p : mesh.points) {
    write_point(out, p);
    out << '\n';
  }
  for (const Tri& f : mesh.faces) out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
}

void write_obj(std::ostream& out, const TriangleMesh& mesh) {
  out << "# organsim surface, metres\n";
  for (const Vec3& p : mesh.points) {
    out << "v ";
    write_point(out, p);
    out << '\n';
  }
  for (const Tri& f : mesh.faces) out << "f " << f[0] + 1 << ' ' << f[1] + 1 << ' ' << f[2] + 1 << '\n';
}

}  // namespace organsim::mesh_io
