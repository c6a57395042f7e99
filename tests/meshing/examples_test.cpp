// The committed example surfaces are valid Mesh_3 input as they are: closed,
// outward, not self-intersecting, of the stated sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/mesh/example_shapes.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "meshing/surface_check.h"

namespace organsim {
namespace examples_test {
namespace {

TriangleMesh example(const char* name) {
  return read_surface(std::filesystem::path(ORGANSIM_SOURCE_DIR) / "examples" / name);
}

Vec3 extent(const TriangleMesh& m) {
  Vec3 lo = m.points.front(), hi = lo;
  for (const Vec3& p : m.points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return hi - lo;
}

TEST(Examples, PassTheSurfaceChecksWithoutRepairs) {
  for (const char* name : {"liver.off", "sphere.off", "box.off"}) {
    std::vector<std::string> notes;
    const TriangleMesh checked = check_surface(example(name), name, notes);
    EXPECT_TRUE(notes.empty()) << name << ": " << (notes.empty() ? "" : notes[0]);
    EXPECT_GT(surface_volume(checked), 0.0) << name;
  }
}

TEST(Examples, HaveTheDocumentedSizes) {
  // Liver: about 0.21 x 0.15 x 0.10 m (a real liver is ~0.2 x 0.15 x 0.1 m), ~1.24 litres.
  const TriangleMesh liver = example("liver.off");
  const Vec3 size = extent(liver);
  EXPECT_NEAR(size.x(), 0.21, 0.02);
  EXPECT_NEAR(size.y(), 0.15, 0.02);
  EXPECT_NEAR(size.z(), 0.10, 0.02);
  EXPECT_NEAR(surface_volume(liver), 1.24e-3, 0.05e-3);
  EXPECT_EQ(liver.faces.size(), 5120u);
  // Sphere of radius 0.05 m: the icosphere's volume is within 0.5 % of the sphere's.
  const double r = 0.05;
  EXPECT_NEAR(surface_volume(example("sphere.off")), 4.0 / 3.0 * std::numbers::pi * r * r * r, 0.005 * 5.24e-4);
  // Box 0.10 x 0.08 x 0.06 m.
  EXPECT_NEAR(surface_volume(example("box.off")), 0.10 * 0.08 * 0.06, 1e-12);
}

}  // namespace
}  // namespace examples_test
}  // namespace organsim
