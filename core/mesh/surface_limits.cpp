// Range checks on a surface's numbers before meshing (see surface_limits.h).
#include "core/mesh/surface_limits.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {

std::string vertex_text(const std::vector<Vec3>& points, int32_t v) {
  const Vec3& p = points[static_cast<size_t>(v)];
  return "vertex " + std::to_string(v) + " (" + format_number(p.x(), "%.17g") + " " + format_number(p.y(), "%.17g") +
         " " + format_number(p.z(), "%.17g") + ")";
}

// "If the file is in millimetres, ..." when one common unit would turn a
// surface of `size` m into an organ of 1 cm to 1 m; empty otherwise.
std::string scale_hint(double size) {
  struct Unit {
    const char* name;
    double metres;
  };
  for (const Unit& u : {Unit{"millimetres", 1e-3}, Unit{"centimetres", 1e-2}, Unit{"micrometres", 1e-6},
                        Unit{"kilometres", 1e3}}) {
    const double scaled = size * u.metres;
    if (scaled >= 0.01 && scaled <= 1.0) {
      return "; if the file is in " + std::string(u.name) + ", scale it by " + format_number(u.metres) +
             " (organsim mesh --scale " + format_number(u.metres) + ", or \"scale\": " + format_number(u.metres) +
             " in the scenario's mesh) to get " + format_number(scaled) + " m";
    }
  }
  return "";
}

}  // namespace

double check_surface_limits(const TriangleMesh& surface, const std::string& source) {
  const auto npoint = static_cast<int64_t>(surface.points.size());
  std::vector<int32_t> used;
  for (size_t f = 0; f < surface.faces.size(); ++f) {
    for (int32_t v : surface.faces[f]) {
      if (v < 0 || v >= npoint) {
        throw input_error(source, "face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                                      ", expected an index in [0, " + std::to_string(npoint) + ")");
      }
      used.push_back(v);
    }
  }
  if (used.empty()) throw input_error(source, "no faces (expected a closed triangle surface)");
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());

  const std::vector<Vec3>& p = surface.points;
  for (int32_t v : used) {
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(p[v][c])) throw input_error(source, vertex_text(p, v) + " has a non-finite coordinate");
      if (std::fpclassify(p[v][c]) == FP_SUBNORMAL) {
        throw input_error(source, vertex_text(p, v) + " has a denormal coordinate (below 2.2e-308 in magnitude); "
                                                      "expected 0 or a normal number of metres");
      }
    }
  }

  // Size first (std::hypot does not overflow for coordinates near 1e300; an
  // extent beyond the double range is inf, which libstdc++'s hypot turns
  // into NaN, so it is kept apart).
  Vec3 lo = p[used.front()], hi = lo;
  for (int32_t v : used) {
    lo = lo.cwiseMin(p[v]);
    hi = hi.cwiseMax(p[v]);
  }
  const Vec3 extent = hi - lo;
  const double size = extent.allFinite() ? std::hypot(extent.x(), extent.y(), extent.z()) : INFINITY;
  if (!(size >= kMinSurfaceSize && size <= kMaxSurfaceSize)) {
    throw input_error(source, "the surface is " + format_number(size) + " m across (bounding-box diagonal); expected " +
                                  "an organ between " + format_number(kMinSurfaceSize) + " m and " +
                                  format_number(kMaxSurfaceSize) + " m, in metres" + scale_hint(size));
  }
  for (int32_t v : used) {
    if (p[v].cwiseAbs().maxCoeff() > kMaxSurfaceDistance) {
      throw input_error(source, vertex_text(p, v) + " is more than " + format_number(kMaxSurfaceDistance) +
                                    " m from the origin; expected coordinates in metres near the origin "
                                    "(move the surface there first)");
    }
  }

  // Exact duplicates among the used vertices: Mesh_3 would see two points
  // where the surface has one.
  std::vector<int32_t> order = used;
  std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {
    return std::lexicographical_compare(p[a].data(), p[a].data() + 3, p[b].data(), p[b].data() + 3);
  });
  for (size_t i = 1; i < order.size(); ++i) {
    if (p[order[i - 1]] == p[order[i]]) {
      const int32_t a = std::min(order[i - 1], order[i]), b = std::max(order[i - 1], order[i]);
      throw input_error(source, vertex_text(p, a) + " and vertex " + std::to_string(b) +
                                    " are at the same position; merge duplicate vertices first (e.g. MeshLab's "
                                    "'Merge Close Vertices')");
    }
  }

  // Degenerate faces (a repeated or collinear corner), and the plane of the largest face.
  // The cross product is scaled by 1/size^2 so no term can overflow.
  double largest = 0;
  Vec3 normal{0, 0, 0};
  size_t largest_face = 0;
  for (size_t f = 0; f < surface.faces.size(); ++f) {
    const Tri& t = surface.faces[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      throw input_error(source, "face " + std::to_string(f) + " repeats a vertex (degenerate triangle); remove it");
    }
    const Vec3 n = ((p[t[1]] - p[t[0]]) / size).cross((p[t[2]] - p[t[0]]) / size);
    const double twice_area = n.norm();  // relative to size^2
    if (!(twice_area > 1e-15)) {
      throw input_error(source, "face " + std::to_string(f) + " has (almost) zero area: its corners " +
                                    std::to_string(t[0]) + ", " + std::to_string(t[1]) + ", " + std::to_string(t[2]) +
                                    " are collinear or coincide; remove it");
    }
    if (twice_area > largest) {
      largest = twice_area;
      normal = n / twice_area;
      largest_face = f;
    }
  }
  const Vec3& origin = p[surface.faces[largest_face][0]];
  double thickness = 0;
  for (int32_t v : used) thickness = std::max(thickness, std::abs(normal.dot(p[v] - origin)));
  if (thickness <= kFlatTolerance * size) {
    throw input_error(source, "all points lie in one plane (within " + format_number(thickness) +
                                  " m): a flat surface encloses no volume to mesh");
  }
  return size;
}

}  // namespace organsim
