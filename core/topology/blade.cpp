#include "core/topology/blade.h"

#include <cmath>

namespace organsim {

bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Moeller-Trumbore: p + s (q - p) = a + u (b - a) + v (c - a).
  const Vec3 dir = q - p, e1 = b - a, e2 = c - a;
  const Vec3 h = dir.cross(e2);
  const double det = e1.dot(h);
  // Parallel (or a degenerate triangle, e.g. a blade that did not move):
  // relative to the sizes involved, so the test does not depend on units.
  const double scale = dir.norm() * e1.norm() * e2.norm();
  if (!(std::abs(det) > 1e-12 * scale)) return false;
  const double inv = 1.0 / det;
  const Vec3 s = p - a;
  const double u = inv * s.dot(h);
  if (u < 0 || u > 1) return false;
  const Vec3 r = s.cross(e1);
  const double v = inv * dir.dot(r);
  if (v < 0 || u + v > 1) return false;
  const double t = inv * e2.dot(r);
  return t >= 0 && t <= 1;
}

std::vector<int32_t> faces_cut_by_blade(const BladeSweep& sweep, const TetFaces& faces, const std::vector<Tet>& tets,
                                        const std::vector<Vec3>& x, const std::vector<uint8_t>& separated) {
  const Vec3 lo = sweep.a0.cwiseMin(sweep.b0).cwiseMin(sweep.a1).cwiseMin(sweep.b1);
  const Vec3 hi = sweep.a0.cwiseMax(sweep.b0).cwiseMax(sweep.a1).cwiseMax(sweep.b1);
  auto centroid = [&](int32_t t) {
    const Tet& k = tets[t];
    return Vec3(0.25 * (x[k[0]] + x[k[1]] + x[k[2]] + x[k[3]]));
  };
  std::vector<int32_t> cut;
  for (int32_t f = 0; f < faces.nface(); ++f) {
    if (separated[f]) continue;
    const Vec3 p = centroid(faces.tets[f][0]), q = centroid(faces.tets[f][1]);
    // Cheap rejection: the segment's box misses the sweep's box.
    if ((p.cwiseMax(q).array() < lo.array()).any() || (p.cwiseMin(q).array() > hi.array()).any()) continue;
    if (segment_crosses_triangle(p, q, sweep.a0, sweep.b0, sweep.b1) ||
        segment_crosses_triangle(p, q, sweep.a0, sweep.b1, sweep.a1))
      cut.push_back(f);
  }
  return cut;
}

}  // namespace organsim
