// STL surfaces, ASCII and binary. STL stores every triangle with its own three
// corners; corners with exactly equal coordinates are welded into one vertex.
#include <array>
#include <cstring>
#include <map>
#include <ostream>

#include "core/mesh/mesh_io_detail.h"

namespace organsim::mesh_io {

namespace {

class Welder {
 public:
  explicit Welder(TriangleMesh& mesh) : mesh_(mesh) {}
  int32_t add(double x, double y, double z) {
    // +0.0 turns -0.0 into 0.0 so both weld; the comparison is exact otherwise.
    const std::array<double, 3> key{x + 0.0, y + 0.0, z + 0.0};
    const auto [it, inserted] = ids_.try_emplace(key, static_cast<int32_t>(mesh_.points.size()));
    if (inserted) mesh_.points.emplace_back(x, y, z);
    return it->second;
  }

 private:
  TriangleMesh& mesh_;
  std::map<std::array<double, 3>, int32_t> ids_;
};

TriangleMesh read_stl_binary(std::string_view bytes, uint32_t count) {
  TriangleMesh mesh;
  Welder welder(mesh);
  mesh.faces.reserve(count);
  for (uint32_t f = 0; f < count; ++f) {
    const char* record = bytes.data() + 84 + 50 * static_cast<size_t>(f);
    float c[12];  // normal, then three corners (little endian, as on this host)
    std::memcpy(c, record, sizeof c);
    Tri tri{};
    for (int k = 0; k < 3; ++k) tri[k] = welder.add(c[3 + 3 * k], c[4 + 3 * k], c[5 + 3 * k]);
    mesh.faces.push_back(tri);
  }
  return mesh;
}

TriangleMesh read_stl_ascii(std::string_view text, const std::string& source) {
  TokenReader in(text, source, 0);
  TriangleMesh mesh;
  Welder welder(mesh);
  if (in.next("'solid'") != "solid") in.fail("expected 'solid'");
  in.skip_line();  // the solid's name
  // Each solid ends with "endsolid": a file cut short ends without it.
  while (true) {
    if (in.at_end()) in.fail("the file ends without 'endsolid' (cut short?)");
    const std::string_view word = in.next("'facet' or 'endsolid'");
    if (word == "endsolid") {
      in.skip_line();
      if (in.at_end()) break;
      if (in.next("'solid'") != "solid") in.fail("expected 'solid' after 'endsolid'");
      in.skip_line();
      continue;
    }
    if (word != "facet") in.fail("expected 'facet' or 'endsolid', got '" + std::string(word) + "'");
    in.skip_line();  // normal nx ny nz: recomputed from the corners when needed
    if (in.next("'outer'") != "outer" || in.next("'loop'") != "loop") in.fail("expected 'outer loop'");
    std::vector<int32_t> corners;
    while (in.peek() == "vertex") {
      in.next("'vertex'");
      const double x = in.next_double("a vertex x coordinate");
      const double y = in.next_double("a vertex y coordinate");
      const double z = in.next_double("a vertex z coordinate");
      corners.push_back(welder.add(x, y, z));
    }
    if (corners.size() != 3) {
      in.fail("facet " + std::to_string(mesh.faces.size()) + " has " + std::to_string(corners.size()) +
              " vertices; not a triangle mesh (expected 3)");
    }
    if (in.next("'endloop'") != "endloop") in.fail("expected 'endloop'");
    if (in.next("'endfacet'") != "endfacet") in.fail("expected 'endfacet'");
    mesh.faces.push_back({corners[0], corners[1], corners[2]});
  }
  return mesh;
}

}  // namespace

TriangleMesh read_stl(std::string_view bytes, const std::string& source) {
  // Binary STL is an 80-byte header, a uint32 count and 50 bytes per facet.
  // The header may start with "solid" or "COLOR=", so decide by the size.
  if (bytes.size() >= 84) {
    uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    if (84 + 50 * static_cast<uint64_t>(count) == bytes.size()) return read_stl_binary(bytes, count);
  }
  size_t start = 0;
  while (start < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[start]))) ++start;
  if (bytes.substr(start, 5) != "solid") {
    throw input_error(source, "neither binary STL (size " + std::to_string(bytes.size()) +
                                  " bytes is not 84 + 50 x the facet count in the header) nor ASCII STL "
                                  "(does not start with 'solid')");
  }
  return read_stl_ascii(bytes, source);
}

void write_stl_binary(std::ostream& out, const TriangleMesh& mesh) {
  char header[80] = {};
  std::strncpy(header, "organsim binary STL, metres", sizeof header - 1);
  out.write(header, 80);
  const auto count = static_cast<uint32_t>(mesh.faces.size());
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (const Tri& f : mesh.faces) {
    const Vec3& a = mesh.points[f[0]];
    const Vec3& b = mesh.points[f[1]];
    const Vec3& c = mesh.points[f[2]];
    const Vec3 n = (b - a).cross(c - a).normalized();
    float record[12];
    for (int k = 0; k < 3; ++k) {
      record[k] = static_cast<float>(n[k]);
      record[3 + k] = static_cast<float>(a[k]);
      record[6 + k] = static_cast<float>(b[k]);
      record[9 + k] = static_cast<float>(c[k]);
    }
    out.write(reinterpret_cast<const char*>(record), sizeof record);
    const char attribute[2] = {0, 0};
    out.write(attribute, 2);
  }
}

}  // namespace organsim::mesh_io
