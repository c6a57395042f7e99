// Surface readers: round trips for every format and the traps of real files.
#include <gtest/gtest.h>

#include <cstring>

#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "mesh_io_test_util.h"

namespace organsim {
namespace mesh_io_surface_test {
namespace {

using testing::error_message;
using testing::fresh_test_dir;
using testing::octahedron;
using testing::write_fixture;

TEST(SurfaceIo, OctahedronIsOutwardWithVolumeFourThirds) {
  // The fixture itself: the divergence-theorem volume of the octahedron |x|+|y|+|z| <= 1 is 4/3.
  EXPECT_NEAR(surface_volume(octahedron()), 4.0 / 3.0, 1e-12);
}

TEST(SurfaceIo, RoundTripEveryFormat) {
  const auto dir = fresh_test_dir("mesh_io");
  const TriangleMesh original = octahedron();
  for (const char* ext : {".off", ".obj", ".stl", ".ply"}) {
    const auto path = dir / (std::string("octa") + ext);
    write_surface(path, original);
    const TriangleMesh back = read_surface(path);
    ASSERT_EQ(back.points.size(), 6u) << ext;  // STL is welded back to 6 points
    ASSERT_EQ(back.faces.size(), 8u) << ext;
    // Coordinates are exact in float, so even STL gives them back exactly;
    // the volume (orientation kept) must be the same.
    EXPECT_NEAR(surface_volume(back), 4.0 / 3.0, 1e-12) << ext;
  }
}

TEST(SurfaceIo, ObjWithNormalsTwoSpacesMissingMtllibAndNegativeIndices) {
  const auto dir = fresh_test_dir("mesh_io");
  const auto path = write_fixture(dir / "trap.obj",
                                  "# exported by something\nmtllib does_not_exist.mtl\no octa\n"
                                  "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
                                  "vn 0 0 1\nvn 0 1 0\nvn 1 0 0\nvt 0 0\nusemtl skin\ns 1\n"
                                  "f  1//1 3//2 5//3\n"       // two spaces, normal indices
                                  "f 3/1/1 2/1/2 5/1/3\n"     // v/vt/vn
                                  "f 2 4 5\r\n"               // CRLF line end
                                  "f -3 -6 -2\n"              // relative: 4 1 5
                                  "f 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n");
  const TriangleMesh m = read_surface(path);
  ASSERT_EQ(m.points.size(), 6u);
  ASSERT_EQ(m.faces.size(), 8u);
  EXPECT_EQ(m.faces[3], (Tri{3, 0, 4}));  // negative indices count back from the last vertex read
  EXPECT_NEAR(surface_volume(m), 4.0 / 3.0, 1e-12);
}

std::string binary_stl(const TriangleMesh& m, const std::string& header_start) {
  std::string bytes(80, '\0');
  std::memcpy(bytes.data(), header_start.data(), header_start.size());
  const auto count = static_cast<uint32_t>(m.faces.size());
  bytes.append(reinterpret_cast<const char*>(&count), 4);
  for (const Tri& f : m.faces) {
    float record[12] = {};
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) record[3 + 3 * k + c] = static_cast<float>(m.points[f[k]][c]);
    }
    bytes.append(reinterpret_cast<const char*>(record), sizeof record);
    bytes.append(2, '\0');
  }
  return bytes;
}

TEST(SurfaceIo, BinaryStlWithSolidOrColorHeaderIsWeldedExactly) {
  const auto dir = fresh_test_dir("mesh_io");
  for (const std::string header : {"solid but actually binary", "COLOR=\xff\x00\x00\xff"}) {
    const auto path = write_fixture(dir / "octa.stl", binary_stl(octahedron(), header));
    const TriangleMesh m = read_surface(path);
    EXPECT_EQ(m.points.size(), 6u) << header;  // 24 corners welded to 6 points
    EXPECT_EQ(m.faces.size(), 8u) << header;
    EXPECT_NEAR(surface_volume(m), 4.0 / 3.0, 1e-12) << header;
  }
}

TEST(SurfaceIo, AsciiStlIsWelded) {
  const auto dir = fresh_test_dir("mesh_io");
  std::string text = "solid octa\n";
  const TriangleMesh o = octahedron();
  for (const Tri& f : o.faces) {
    text += "  facet normal 0 0 0\n    outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = o.points[f[k]];
      // -0 and 0 are the same point and must weld.
      text += "      vertex " + std::to_string(p.x()) + " " + (p.y() == 0 ? std::string("-0") : std::to_string(p.y())) + " " +
              std::to_string(p.z()) + "\n";
    }
    text += "    endloop\n  endfacet\n";
  }
  text += "endsolid octa\n";
  const TriangleMesh m = read_surface(write_fixture(dir / "octa.stl", text));
  EXPECT_EQ(m.points.size(), 6u);
  EXPECT_EQ(m.faces.size(), 8u);
  EXPECT_NEAR(surface_volume(m), 4.0 / 3.0, 1e-6);
}

std::string binary_ply(const TriangleMesh& m, bool big_endian) {
  std::string bytes = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                      " 1.0\ncomment fixture\nelement vertex " + std::to_string(m.points.size()) +
                      "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
                      "element face " + std::to_string(m.faces.size()) +
                      "\nproperty list uchar int vertex_indices\nproperty float quality\nend_header\n";
  const auto put = [&](const void* data, size_t size) {
    std::string raw(static_cast<const char*>(data), size);
    if (big_endian) std::reverse(raw.begin(), raw.end());
    bytes += raw;
  };
  for (const Vec3& p : m.points) {
    for (int c = 0; c < 3; ++c) {
      const auto v = static_cast<float>(p[c]);
      put(&v, 4);
    }
    bytes += '\x7f';
  }
  for (const Tri& f : m.faces) {
    bytes += '\x03';
    for (int32_t v : f) put(&v, 4);
    const float quality = 0.5f;
    put(&quality, 4);
  }
  return bytes;
}

TEST(SurfaceIo, BinaryPlyBothByteOrders) {
  const auto dir = fresh_test_dir("mesh_io");
  for (bool big : {false, true}) {
    const TriangleMesh m = read_surface(write_fixture(dir / "octa.ply", binary_ply(octahedron(), big)));
    EXPECT_EQ(m.points.size(), 6u) << big;
    EXPECT_EQ(m.faces.size(), 8u) << big;
    EXPECT_NEAR(surface_volume(m), 4.0 / 3.0, 1e-12) << big;
  }
}

TEST(SurfaceIo, ErrorsNameTheFileAndTheProblem) {
  const auto dir = fresh_test_dir("mesh_io");
  const std::string missing = (dir / "missing.off").string();
  std::string msg = error_message([&] { read_surface(missing); });
  EXPECT_NE(msg.find(missing), std::string::npos) << msg;
  EXPECT_NE(msg.find("no such file"), std::string::npos) << msg;

  const auto unknown = write_fixture(dir / "octa.xyz", "1 2 3\n");
  msg = error_message([&] { read_surface(unknown); });
  EXPECT_NE(msg.find("octa.xyz"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown surface extension '.xyz'"), std::string::npos) << msg;

  const auto quad = write_fixture(dir / "quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  msg = error_message([&] { read_surface(quad); });
  EXPECT_NE(msg.find("quad.off"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 7"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not a triangle mesh"), std::string::npos) << msg;

  const auto range = write_fixture(dir / "range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 3\n");
  msg = error_message([&] { read_surface(range); });
  EXPECT_NE(msg.find("refers to vertex 3"), std::string::npos) << msg;

  const auto obj_range = write_fixture(dir / "range.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  msg = error_message([&] { read_surface(obj_range); });
  EXPECT_NE(msg.find("line 3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("only 2 vertices"), std::string::npos) << msg;

  const auto garbage = write_fixture(dir / "garbage.stl", "this is not an stl file at all");
  msg = error_message([&] { read_surface(garbage); });
  EXPECT_NE(msg.find("neither binary STL"), std::string::npos) << msg;

  // A corrupt count must not make the reader allocate gigabytes first.
  const auto huge = write_fixture(dir / "huge.off", "OFF\n1000000000 1 0\n0 0 0\n");
  msg = error_message([&] { read_surface(huge); });
  EXPECT_NE(msg.find("1000000000 vertices cannot fit in the rest of the file"), std::string::npos) << msg;

  const auto truncated = write_fixture(dir / "trunc.off", "OFF\n3 1 0\n0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0\n");
  msg = error_message([&] { read_surface(truncated); });
  EXPECT_NE(msg.find("expected a vertex"), std::string::npos) << msg;
}

}  // namespace
}  // namespace mesh_io_surface_test
}  // namespace organsim
