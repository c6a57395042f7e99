#include "core/sim/contact_stiffness.h"

#include <stdexcept>

#include "core/physics/force_law.h"

namespace organsim {

namespace {

// dq/dc of a triangle's closest point q to c: the projector onto the feature
// q lies on, read from its barycentric weights (three non-zero: the face;
// two: an edge; one: a vertex, which stays put).
Mat3 closest_point_follow(const double w[3], const Vec3& x0, const Vec3& x1, const Vec3& x2) {
  const Vec3* x[3] = {&x0, &x1, &x2};
  int on[3], n = 0;
  for (int i = 0; i < 3; ++i)
    if (w[i] > 0) on[n++] = i;
  if (n == 3) {
    const Vec3 m = (x1 - x0).cross(x2 - x0);
    const double len = m.norm();
    if (len > 0) return Mat3::Identity() - (m / len) * (m / len).transpose();
    return Mat3::Zero();
  }
  if (n == 2) {
    const Vec3 e = *x[on[1]] - *x[on[0]];
    const double len = e.norm();
    if (len > 0) return (e / len) * (e / len).transpose();
  }
  return Mat3::Zero();
}

}  // namespace

Mat3 reference_push_stiffness(const std::vector<Vec3>& x, const Vec3& center, double radius, double stiffness,
                              const std::vector<double>& scale) {
  Mat3 k = Mat3::Zero();
  for (size_t i = 0; i < x.size(); ++i) {
    const Vec3 offset = x[i] - center;
    const double dist = offset.norm();
    if (!(dist < radius)) continue;
    const Vec3 n = dist > 0 ? Vec3(offset / dist) : Vec3(0, 0, 1);  // as force_law::push_penalty
    const double ks = stiffness * (scale.empty() ? 1.0 : scale[i]);
    k -= force_law::push_penalty_center_jacobian(n, dist, radius, ks, Mat3::Zero().eval());
  }
  return k;
}

Mat3 reference_surface_stiffness(const Model& model, const std::vector<Vec3>& x, const Vec3& center, double radius,
                                 double stiffness) {
  Mat3 k = Mat3::Zero();
  for (const Tri& t : model.surface) {
    // A triangle whose box stays R away from c cannot touch (cheap: one pass per tick at liver size).
    const Vec3 lo = x[t[0]].cwiseMin(x[t[1]]).cwiseMin(x[t[2]]), hi = x[t[0]].cwiseMax(x[t[1]]).cwiseMax(x[t[2]]);
    if ((center.cwiseMax(lo).cwiseMin(hi) - center).squaredNorm() >= radius * radius) continue;
    double share[3];
    for (int i = 0; i < 3; ++i) share[i] = model.tool_scale(t[i]) / model.surface_count(t[i]);
    Vec3 f;
    double w[3];
    const Vec3 &x0 = x[t[0]], &x1 = x[t[1]], &x2 = x[t[2]];
    if (!force_law::sphere_triangle_penalty(center, radius, x0, x1, x2, stiffness, share, f, w)) continue;
    // f = k_t (R - d) n: its direction and size give n and d back.
    const double kt = stiffness * force_law::triangle_penalty_scale(share);
    if (!(kt > 0)) continue;  // no force, no stiffness (and no direction to read back)
    const Vec3 q = w[0] * x0 + w[1] * x1 + w[2] * x2;
    const double dist = (q - center).norm();
    const Vec3 n = f / (kt * (radius - dist));
    k -= force_law::push_penalty_center_jacobian(n, dist, radius, kt, closest_point_follow(w, x0, x1, x2));
  }
  return k;
}

Mat3 layered_surface_stiffness(const Model& model, const std::vector<Vec3>& x, const Vec3& center, double radius,
                               double stiffness, const ContactLayer& layer) {
  // The triangles that can touch while the centre moves by h: all the
  // differences see the same set, and a reply costs a few of them, not a
  // pass over the surface per difference.
  constexpr double h = 1e-7;  // m: truncation and rounding both far below 1e-6 of k
  const double reach = radius + 2 * h;
  std::vector<const Tri*> near;
  for (const Tri& t : model.surface) {
    const Vec3 lo = x[t[0]].cwiseMin(x[t[1]]).cwiseMin(x[t[2]]), hi = x[t[0]].cwiseMax(x[t[1]]).cwiseMax(x[t[2]]);
    if ((center.cwiseMax(lo).cwiseMin(hi) - center).squaredNorm() < reach * reach) near.push_back(&t);
  }
  force_law::HertzLayer hertz;
  std::vector<Vec3> penalty;
  // The layered reaction, as reference_surface_forces gives it, over `near`.
  const auto reaction = [&](const Vec3& c) {
    hertz.clear();
    penalty.clear();
    for (const Tri* t : near) {
      double share[3], w[3];
      for (int i = 0; i < 3; ++i) share[i] = model.tool_scale((*t)[i]) / model.surface_count((*t)[i]);
      Vec3 f;
      if (!force_law::sphere_triangle_penalty(c, radius, x[(*t)[0]], x[(*t)[1]], x[(*t)[2]], stiffness, share, f, w))
        continue;
      const TriangleLayer tl = triangle_layer(layer, *t);
      hertz.add(f.data(), stiffness * force_law::triangle_penalty_scale(share), tl.punch_radius, tl.e_star);
      penalty.push_back(f);
    }
    hertz.solve(radius);
    Vec3 F = Vec3::Zero();
    for (size_t i = 0; i < penalty.size(); ++i) F -= hertz.factor(i) * penalty[i];
    return F;
  };
  Mat3 k;
  for (int j = 0; j < 3; ++j) {
    Vec3 step = Vec3::Zero();
    step[j] = h;
    k.col(j) = (reaction(center + step) - reaction(center - step)) / (2 * h);
  }
  return k;
}

Mat3 attachment_stiffness(const Model& model, const Attachment& held, double stiffness) {
  double k = 0;
  for (int32_t p : held.points) k += stiffness * model.tool_scale(p);
  return -k * Mat3::Identity();
}

Mat3 tool_contact_stiffness(const Model& model, const std::vector<Vec3>& x, const BackendTool& tool,
                            const Vec3& center, const ContactLayer* layer) {
  if (!tool.present || tool.mode != ToolMode::Push) return Mat3::Zero();
  if (tool.hertz_layer) {
    if (!layer) throw std::logic_error("tool_contact_stiffness: the Hertz layer's per-point data is missing");
    return layered_surface_stiffness(model, x, center, tool.radius, tool.contact_stiffness, *layer);
  }
  if (tool.contact == ToolContact::Surface)
    return reference_surface_stiffness(model, x, center, tool.radius, tool.contact_stiffness);
  return reference_push_stiffness(x, center, tool.radius, tool.contact_stiffness, model.tool_k_scale);
}

}  // namespace organsim
