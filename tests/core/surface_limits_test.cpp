// The range checks a surface passes before CGAL Mesh_3 sees it
// (core/mesh/surface_limits.h): each class of bad numbers gets its own
// message naming the file and the vertex or face, and organ-sized surfaces
// pass unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/mesh/example_shapes.h"
#include "core/mesh/surface_limits.h"
#include "mesh_io_test_util.h"

namespace organsim {
namespace surface_limits_test {
namespace {

using testing::error_message;

// A closed tetrahedron with legs of `leg` m from the origin.
TriangleMesh tetrahedron(double leg) {
  return {{{0, 0, 0}, {leg, 0, 0}, {0, leg, 0}, {0, 0, leg}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
}

std::string refusal(const TriangleMesh& surface) {
  const std::string msg = error_message([&] { check_surface_limits(surface, "s.off"); });
  EXPECT_EQ(msg.rfind("s.off: ", 0), 0u) << msg;
  return msg;
}

TEST(SurfaceLimits, OrganSizedSurfacesPassAndReportTheirDiagonal) {
  // sqrt(3) * 0.1 exactly up to rounding: the diagonal of the tet's bounding box.
  EXPECT_NEAR(check_surface_limits(tetrahedron(0.1), "s.off"), std::sqrt(3.0) * 0.1, 1e-15);
  EXPECT_GT(check_surface_limits(make_liver_surface(2), "liver.off"), 0.1);
}

// A closed tetrahedron whose bounding-box diagonal, as check_surface_limits
// computes it (std::hypot of the extent), is exactly `diagonal`: legs
// (L, side, side) with L stepped by one ulp at a time to the value that
// rounds to it (each ulp of L moves the diagonal by about one ulp).
TriangleMesh tetrahedron_with_diagonal(double diagonal, double side) {
  double leg = std::sqrt(diagonal * diagonal - 2 * side * side);
  for (int i = 0; i < 64 && std::hypot(leg, side, side) != diagonal; ++i)
    leg = std::nextafter(leg, std::hypot(leg, side, side) < diagonal ? INFINITY : 0.0);
  EXPECT_EQ(std::hypot(leg, side, side), diagonal);
  return {{{0, 0, 0}, {leg, 0, 0}, {0, side, 0}, {0, 0, side}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
}

// The limits themselves are inclusive: a diagonal of exactly the limit
// passes, one ulp beyond it is refused.
TEST(SurfaceLimits, SizesAtTheLimitsPassAndOneUlpBeyondAreRefused) {
  for (const double limit : {kMinSurfaceSize, kMaxSurfaceSize}) {
    SCOPED_TRACE(limit);
    const double side = 0.3 * limit;
    EXPECT_NO_THROW(check_surface_limits(tetrahedron_with_diagonal(limit, side), "s.off"));
    const double beyond = std::nextafter(limit, limit == kMaxSurfaceSize ? INFINITY : 0.0);
    EXPECT_NE(refusal(tetrahedron_with_diagonal(beyond, side)).find(" m across"), std::string::npos);
  }
}

TEST(SurfaceLimits, AbsurdSizesAreRefusedWithTheSize) {
  TriangleMesh huge = tetrahedron(0.1);
  huge.points[1].x() = 1e300;
  EXPECT_NE(refusal(huge).find("the surface is 1e+300 m across"), std::string::npos);
  EXPECT_NE(refusal(tetrahedron(1e200)).find("1.732e+200 m across"), std::string::npos);
  EXPECT_NE(refusal(tetrahedron(1e-300)).find("1.732e-300 m across"), std::string::npos);
  EXPECT_NE(refusal(tetrahedron(1e-9)).find("expected an organ between 0.0001 m and 10 m"), std::string::npos);
  TriangleMesh span = tetrahedron(0.1);  // the box spans more than the largest double
  span.points[1].x() = std::numeric_limits<double>::max();
  span.points[2].x() = -std::numeric_limits<double>::max();
  EXPECT_NE(refusal(span).find("the surface is inf m across"), std::string::npos);
}

TEST(SurfaceLimits, PlausibleSizesInOtherUnitsSuggestTheScale) {
  const std::string mm = refusal(tetrahedron(100));  // 100 mm legs written as 100 "m"
  EXPECT_NE(mm.find("if the file is in millimetres, scale it by 0.001 (organsim mesh --scale 0.001, or \"scale\": "
                    "0.001 in the scenario's mesh) to get 0.1732 m"),
            std::string::npos)
      << mm;
  EXPECT_NE(refusal(tetrahedron(1e5)).find("if the file is in micrometres, scale it by 1e-06"), std::string::npos);
  // No unit makes a nanometre-sized or a 1e200 m surface an organ: no hint.
  EXPECT_EQ(refusal(tetrahedron(1e-9)).find("if the file is in"), std::string::npos);
  EXPECT_EQ(refusal(tetrahedron(1e200)).find("if the file is in"), std::string::npos);
}

TEST(SurfaceLimits, NonFiniteAndDenormalCoordinatesNameTheVertex) {
  TriangleMesh nan = tetrahedron(0.1);
  nan.points[3].z() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(refusal(nan).find("vertex 3 (0 0 nan) has a non-finite coordinate"), std::string::npos);
  TriangleMesh denormal = tetrahedron(0.1);
  denormal.points[2].x() = 1e-310;
  const std::string msg = refusal(denormal);
  EXPECT_NE(msg.find("vertex 2 ("), std::string::npos) << msg;
  EXPECT_NE(msg.find("has a denormal coordinate"), std::string::npos) << msg;
  // An unused vertex is not checked: check_surface drops it before meshing.
  TriangleMesh unused = tetrahedron(0.1);
  unused.points.push_back({std::numeric_limits<double>::infinity(), 0, 0});
  EXPECT_NO_THROW(check_surface_limits(unused, "s.off"));
}

TEST(SurfaceLimits, FarFromTheOriginIsRefused) {
  TriangleMesh far = tetrahedron(0.1);
  for (Vec3& p : far.points) p.y() += 150;
  EXPECT_NE(refusal(far).find("vertex 0 (0 150 0) is more than 100 m from the origin"), std::string::npos);
}

TEST(SurfaceLimits, DuplicateVerticesZeroAreaFacesAndFlatSurfacesAreRefused) {
  TriangleMesh duplicate = tetrahedron(0.1);
  duplicate.points.push_back(duplicate.points[3]);
  duplicate.faces[3][2] = 4;  // face 1 2 3 now uses the copy of vertex 3
  EXPECT_NE(refusal(duplicate).find("vertex 3 (0 0 0.10000000000000001) and vertex 4 are at the same position"),
            std::string::npos);

  TriangleMesh collinear = tetrahedron(0.1);
  collinear.points[2] = {0.05, 0, 0};  // on the edge 0-1
  EXPECT_NE(refusal(collinear).find("face 0 has (almost) zero area: its corners 0, 2, 1 are collinear"),
            std::string::npos);

  // Two triangles back to back: closed, but all in the plane z = 0.
  const TriangleMesh pillow{{{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}}, {{0, 1, 2}, {0, 2, 1}}};
  EXPECT_NE(refusal(pillow).find("all points lie in one plane"), std::string::npos);
  const TriangleMesh almost_flat = make_box_surface({0, 0, 0}, {0.1, 0.1, 1e-13});  // 0.14 m across
  EXPECT_NE(refusal(almost_flat).find("all points lie in one plane"), std::string::npos);
}

TEST(SurfaceLimits, BadIndicesAndNoFacesAreRefused) {
  TriangleMesh bad = tetrahedron(0.1);
  bad.faces[2][1] = 7;
  EXPECT_NE(refusal(bad).find("face 2 refers to vertex 7, expected an index in [0, 4)"), std::string::npos);
  EXPECT_NE(refusal(TriangleMesh{}).find("no faces"), std::string::npos);
}

}  // namespace
}  // namespace surface_limits_test
}  // namespace organsim
