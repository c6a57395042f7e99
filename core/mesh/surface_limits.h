#pragma once
// The numbers a surface must have before CGAL Mesh_3 sees it. Mesh_3 checks
// none of them: a coordinate of 1e300 dies of SIGFPE, a surface 1e200 m
// across hangs, one 1e-300 m across "succeeds" with zero-volume tets. So
// every surface is held to an organ's scale, in metres, here first.
#include <string>

#include "core/mesh/tet_mesh.h"

namespace organsim {

inline constexpr double kMinSurfaceSize = 1e-4;      // m, bounding-box diagonal (0.1 mm)
inline constexpr double kMaxSurfaceSize = 10.0;      // m, bounding-box diagonal
inline constexpr double kMaxSurfaceDistance = 100.0; // m, largest |coordinate|
// Relative to the diagonal L: points closer than this to the plane of the
// largest face make a flat surface (no volume to mesh).
inline constexpr double kFlatTolerance = 1e-9;

// Throws Error(Input) "source: <what is wrong>" for the first problem among
// the vertices that faces use: an index out of range, a non-finite or denormal
// coordinate, a bounding-box diagonal outside [kMinSurfaceSize,
// kMaxSurfaceSize] (suggesting the scale option when another unit would give
// an organ-sized surface), a coordinate beyond kMaxSurfaceDistance, two
// vertices at the same position, a face that repeats a vertex or has zero
// area, or all points in one plane. Returns the diagonal, m.
double check_surface_limits(const TriangleMesh& surface, const std::string& source);

}  // namespace organsim
