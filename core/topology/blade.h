#pragma once
// Blade detection (docs/topology.md). A blade is a straight cutting edge
// (a, b); over one interval it sweeps the quad (a0, b0, b1, a1), taken as the
// two triangles (a0, b0, b1) and (a0, b1, a1). An interior face between tets
// T1 and T2 is cut when the segment between their centroids (in the current
// configuration) crosses one of these triangles.
#include <cstdint>
#include <vector>

#include "core/topology/tet_faces.h"

namespace organsim {

struct BladeSweep {
  Vec3 a0, b0;  // edge ends at the start of the interval, m
  Vec3 a1, b1;  // and at its end, m
};

// Whether the segment p-q meets the triangle (a, b, c), boundaries included.
// A segment in the triangle's plane (no single crossing point) does not.
bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c);

// Interior faces not yet separated that the sweep cuts, ascending face id.
// `x` are the current positions (internal numbering) of the points in `tets`.
std::vector<int32_t> faces_cut_by_blade(const BladeSweep& sweep, const TetFaces& faces, const std::vector<Tet>& tets,
                                        const std::vector<Vec3>& x, const std::vector<uint8_t>& separated);

}  // namespace organsim
