// Boundary extraction (core/mesh/boundary.h): pure topology, no GL needed.
#include <gtest/gtest.h>

#include "core/mesh/boundary.h"
#include "core/mesh/tet_mesh.h"

namespace organsim {
namespace boundary_test {
namespace {

TEST(Boundary, SingleTetHasFourOutwardFaces) {
  const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<Tri> faces = extract_boundary_faces({Tet{0, 1, 2, 3}});
  ASSERT_EQ(faces.size(), 4u);
  const Vec3 centroid = (p[0] + p[1] + p[2] + p[3]) / 4;
  for (const Tri& f : faces) {
    const Vec3 n = (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]);
    const Vec3 c = (p[f[0]] + p[f[1]] + p[f[2]]) / 3;
    // Outward: the normal points away from the tet's centroid (exact
    // arithmetic on these coordinates; any positive value means outward).
    EXPECT_GT(n.dot(c - centroid), 0.0);
  }
  // Divergence theorem on the four faces gives the tet's volume 1/6.
  EXPECT_NEAR(enclosed_volume(p, faces), 1.0 / 6.0, 1e-15);
  const SurfaceTopology topo = surface_topology(faces);
  EXPECT_TRUE(topo.closed_and_oriented());
  EXPECT_EQ(topo.euler_characteristic(), 2);
}

TEST(Boundary, TwoTetsSharingAFaceDropIt) {
  // Second tet mirrors the first through the face (1,2,3); 6 outer faces.
  const std::vector<Tet> tets = {Tet{0, 1, 2, 3}, Tet{4, 1, 3, 2}};
  const std::vector<Tri> faces = extract_boundary_faces(tets);
  EXPECT_EQ(faces.size(), 6u);
  for (const Tri& f : faces) {
    std::array<int32_t, 3> s = f;
    std::sort(s.begin(), s.end());
    EXPECT_NE(s, (std::array<int32_t, 3>{1, 2, 3}));
  }
}

TEST(Boundary, BoxIsClosedSphereLikeAndEnclosesTheBoxVolume) {
  const Vec3 lo(-0.05, 0.02, 0.0), hi(0.07, 0.1, 0.04);
  const int nx = 5, ny = 4, nz = 3;
  const TetMesh mesh = make_box_tet_mesh(lo, hi, nx, ny, nz);
  const std::vector<Tri> faces = extract_boundary_faces(mesh.tets);
  // Each boundary square of the grid is cut into 2 triangles.
  EXPECT_EQ(faces.size(), static_cast<size_t>(4 * (nx * ny + ny * nz + nx * nz)));
  const SurfaceTopology topo = surface_topology(faces);
  EXPECT_EQ(topo.border_edges, 0);
  EXPECT_EQ(topo.nonmanifold_edges, 0);
  EXPECT_EQ(topo.misoriented_edges, 0);
  EXPECT_EQ(topo.euler_characteristic(), 2);  // a sphere's
  const double box_volume = (hi - lo).prod();
  // Rounding only: the sum has ~100 terms of size ~1e-4.
  EXPECT_NEAR(enclosed_volume(mesh.points, faces), box_volume, 1e-12 * 100);
  EXPECT_GT(enclosed_volume(mesh.points, faces), 0.0);  // outward, not inward
}

TEST(Boundary, OrderOfTetsDoesNotChangeTheSurface) {
  TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 2, 2, 2);
  const std::vector<Tri> a = extract_boundary_faces(mesh.tets);
  std::reverse(mesh.tets.begin(), mesh.tets.end());
  EXPECT_EQ(extract_boundary_faces(mesh.tets), a);
}

}  // namespace
}  // namespace boundary_test
}  // namespace organsim
