#pragma once
// Closed triangle surfaces the project makes itself (examples/ and tests):
// no meshes copied from elsewhere. All sizes in metres.
#include <string>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// Unit icosphere: the icosahedron with each face split into 4, `subdivisions`
// times, projected onto the sphere (10 * 4^s + 2 points, 20 * 4^s faces).
TriangleMesh make_icosphere(int subdivisions);

// Sphere of `radius` m about the origin (an icosphere, so slightly smaller in
// volume than the true sphere: 0.3 % at 4 subdivisions).
TriangleMesh make_sphere_surface(double radius, int subdivisions);

// Axis-aligned box [min, max] as 12 outward triangles.
TriangleMesh make_box_surface(const Vec3& min, const Vec3& max);

// A liver-like solid about 0.21 x 0.15 x 0.10 m: a large right lobe and a
// flatter, tapering left lobe, blended smoothly. Star-shaped about the origin,
// so sampling its radius on an icosphere gives a closed, non-self-intersecting,
// outward-oriented surface.
TriangleMesh make_liver_surface(int subdivisions);

// The surface `organsim example SHAPE` writes and examples/ holds ("liver",
// "sphere" of `radius` m, or "box"), rounded to micrometres so the files are
// short and read back exactly. Throws Error(Usage) for another name.
TriangleMesh make_example_surface(const std::string& shape, int subdivisions = 4, double radius = 0.05);

// Rounds every coordinate to a multiple of `quantum` m, so text files stay
// short and read back exactly.
void round_points(TriangleMesh& mesh, double quantum);

}  // namespace organsim
