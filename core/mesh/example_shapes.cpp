// Example surfaces: icosphere, sphere, box and a liver-like blend of ellipsoids.
#include "core/mesh/example_shapes.h"

#include <cmath>
#include <algorithm>
#include <map>
#include <numbers>

#include "core/util/error.h"

namespace organsim {

TriangleMesh make_icosphere(int subdivisions) {
  TriangleMesh mesh;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const double base[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (const auto& p : base) mesh.points.push_back(Vec3(p[0], p[1], p[2]).normalized());
  mesh.faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int32_t, int32_t>, int32_t> midpoints;  // shared by the two faces of an edge
    const auto midpoint = [&](int32_t a, int32_t b) {
      const auto key = std::minmax(a, b);
      const auto [it, inserted] = midpoints.try_emplace({key.first, key.second}, static_cast<int32_t>(mesh.points.size()));
      if (inserted) mesh.points.push_back((mesh.points[a] + mesh.points[b]).normalized());
      return it->second;
    };
    std::vector<Tri> faces;
    faces.reserve(mesh.faces.size() * 4);
    for (const Tri& f : mesh.faces) {
      const int32_t ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      faces.push_back({f[0], ab, ca});
      faces.push_back({f[1], bc, ab});
      faces.push_back({f[2], ca, bc});
      faces.push_back({ab, bc, ca});
    }
    mesh.faces = std::move(faces);
  }
  return mesh;
}

TriangleMesh make_sphere_surface(double radius, int subdivisions) {
  TriangleMesh mesh = make_icosphere(subdivisions);
  for (Vec3& p : mesh.points) p *= radius;
  return mesh;
}

TriangleMesh make_box_surface(const Vec3& min, const Vec3& max) {
  TriangleMesh mesh;
  for (int v = 0; v < 8; ++v) {  // id = x + 2y + 4z, each bit picking min or max
    mesh.points.emplace_back(v & 1 ? max.x() : min.x(), v & 2 ? max.y() : min.y(), v & 4 ? max.z() : min.z());
  }
  mesh.faces = {{0, 2, 3}, {0, 3, 1},   // z = min, normal -z
                {4, 5, 7}, {4, 7, 6},   // z = max, normal +z
                {0, 1, 5}, {0, 5, 4},   // y = min, normal -y
                {2, 6, 7}, {2, 7, 3},   // y = max, normal +y
                {0, 4, 6}, {0, 6, 2},   // x = min, normal -x
                {1, 3, 7}, {1, 7, 5}};  // x = max, normal +x
  return mesh;
}

namespace {

struct Ellipsoid {
  Vec3 centre;     // m
  Vec3 semi_axes;  // m, along the rotated axes
  double yaw;      // rotation about z, rad
};

// Distance from the origin along unit direction d to where the ray leaves the
// ellipsoid (the origin lies inside every ellipsoid used here).
double exit_distance(const Ellipsoid& e, const Vec3& d) {
  const double c = std::cos(e.yaw), s = std::sin(e.yaw);
  // Into the ellipsoid's frame, scaled to the unit sphere: |o + r u| = 1.
  const auto to_unit = [&](const Vec3& v) {
    return Vec3((c * v.x() + s * v.y()) / e.semi_axes.x(), (-s * v.x() + c * v.y()) / e.semi_axes.y(),
                v.z() / e.semi_axes.z());
  };
  const Vec3 o = to_unit(-e.centre);
  const Vec3 u = to_unit(d);
  const double a = u.squaredNorm(), b = 2 * o.dot(u), k = o.squaredNorm() - 1;  // k < 0: origin inside
  return (-b + std::sqrt(b * b - 4 * a * k)) / (2 * a);
}

}  // namespace

TriangleMesh make_liver_surface(int subdivisions) {
  // Lobes chosen by eye for a liver-like silhouette of realistic size; each
  // contains the origin, so every ray from it leaves each lobe exactly once.
  const Ellipsoid lobes[] = {
      {Vec3(0.025, 0.000, 0.000), Vec3(0.075, 0.072, 0.060), 0.0},    // right lobe
      {Vec3(-0.045, 0.010, 0.000), Vec3(0.065, 0.050, 0.040), 0.15},  // left lobe
      {Vec3(0.010, -0.030, -0.010), Vec3(0.045, 0.035, 0.030), 0.0},  // caudate bulge
  };
  // Smooth maximum of the lobes' radii (a p-norm): their union, with blended
  // creases instead of sharp ones.
  constexpr double kSharpness = 6;
  TriangleMesh mesh = make_icosphere(subdivisions);
  const Vec3 fossa = Vec3(0.35, -0.35, -0.87).normalized();
  for (Vec3& p : mesh.points) {
    const Vec3 d = p.normalized();
    double sum = 0;
    for (const Ellipsoid& e : lobes) sum += std::pow(exit_distance(e, d), kSharpness);
    double r = std::pow(sum, 1.0 / kSharpness);
    // A shallow dent on the underside (the gallbladder fossa), below the right lobe.
    r *= 1.0 - 0.10 * std::exp(-(d - fossa).squaredNorm() / 0.05);
    p = r * d;
  }
  // Wedge: thick on the right, thin on the left, with a flatter underside.
  // (x, y, z) -> (x, y, f(x, z)) with f increasing in z is one-to-one, so the
  // surface stays closed and free of self-intersections.
  for (Vec3& p : mesh.points) {
    const double t = std::clamp((p.x() + 0.11) / 0.17, 0.0, 1.0);
    const double thick = 0.45 + 0.55 * t * t * (3 - 2 * t);  // smoothstep from left to right
    const double z = p.z() < 0 ? 0.7 * p.z() : p.z();
    p.z() = z * thick + 0.012 * (1 - thick);  // the thin left lobe sits a little higher
  }
  return mesh;
}

void round_points(TriangleMesh& mesh, double quantum) {
  // Divide by the integer count per metre: the result is the double nearest
  // the decimal, so it prints short (0.012346, not 0.012346000000000001).
  const double per_metre = std::round(1.0 / quantum);
  for (Vec3& p : mesh.points) {
    for (int c = 0; c < 3; ++c) p[c] = std::round(p[c] * per_metre) / per_metre;
  }
}

TriangleMesh make_example_surface(const std::string& shape, int subdivisions, double radius) {
  TriangleMesh surface;
  if (shape == "liver") surface = make_liver_surface(subdivisions);
  else if (shape == "sphere") surface = make_sphere_surface(radius, subdivisions);
  else if (shape == "box") surface = make_box_surface(Vec3(-0.05, -0.04, -0.03), Vec3(0.05, 0.04, 0.03));
  else throw Error(ErrorKind::Usage, "unknown example shape '" + shape + "', expected liver, sphere or box");
  round_points(surface, 1e-6);  // micrometres
  return surface;
}

}  // namespace organsim
