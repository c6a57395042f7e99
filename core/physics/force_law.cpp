#include "core/physics/force_law.h"

#include <cmath>

namespace organsim::force_law {

double shear_barrier(double J) {
  const double jm = kShearElementMinJ;
  if (J >= jm) return -std::log(J);
  return -std::log(jm) - (J - jm) / jm + (J - jm) * (J - jm) / (2 * jm * jm);
}

namespace {
// The Hertz force at contact radius a: 4 E* a^3 / (3 R).
double hertz_force_at(double a, double e_star, double radius) { return 4 * e_star * a * a * a / (3 * radius); }
}  // namespace

double hertz_layer_offset(double force, double e_star, double radius, double punch_radius) {
  if (!(force > 0)) return 0;
  const double a = std::cbrt(3 * force * radius / (4 * e_star));
  if (a >= punch_radius) return punch_radius * punch_radius / (3 * radius);
  return a * a / radius - force / (2 * e_star * punch_radius);
}

double HertzLayer::force_along(double delta) const {
  double g = 0;
  for (const Touch& t : touches_) g += t.c * t.m * hertz_layer_factor(t.m, t.k, t.c, delta);
  return g;
}

double HertzLayer::stiffness_along(double delta) const {
  double k = 0;
  for (const Touch& t : touches_)
    if (t.m - t.k * t.c * delta > 0) k += t.k * t.c * t.c;
  return k;
}

void HertzLayer::solve(double radius) {
  delta_ = 0;
  double sum[3] = {0, 0, 0};
  for (const Touch& t : touches_)
    for (int i = 0; i < 3; ++i) sum[i] += t.f[i];
  const double linear = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
  if (!(linear > 0) || !(weight_ > 0)) return;
  for (Touch& t : touches_) t.c = t.m > 0 ? (t.f[0] * sum[0] + t.f[1] * sum[1] + t.f[2] * sum[2]) / (t.m * linear) : 0;
  const double e_star = this->e_star(), a_h = punch_radius();
  // Beyond a_h the offset is constant.
  const double beyond = a_h * a_h / (3 * radius);
  if (force_along(beyond) >= hertz_force_at(a_h, e_star, radius)) {
    delta_ = beyond;
    return;
  }
  // Below: h(a) = F(a) - G(delta(a)) rises strictly with the Hertz radius a
  // on [0, a_h] (F' = 4 E* a^2 / R, delta' = 2 a (1 - a / a_h) / R >= 0, G
  // falling), h(0) = -|F_lin| < 0 < h(a_h).
  const auto delta_at = [&](double a) { return hertz_layer_offset_at(a, radius, a_h); };
  double lo = 0, hi = a_h, a = a_h;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double d = delta_at(a), value = hertz_force_at(a, e_star, radius) - force_along(d);
    if (value == 0) break;
    (value < 0 ? lo : hi) = a;
    const double slope = 4 * e_star * a * a / radius + stiffness_along(d) * 2 * a * (1 - a / a_h) / radius;
    double next = slope > 0 ? a - value / slope : lo;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool settled = std::abs(next - a) <= 1e-13 * a_h;
    a = next;
    if (settled) break;
  }
  delta_ = delta_at(a);
}

}  // namespace organsim::force_law
