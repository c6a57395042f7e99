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

double hertz_layer_force(double linear_force, double stiffness, double e_star, double radius, double punch_radius) {
  if (!(linear_force > 0)) return 0;
  // Beyond a_h the offset is constant: F = F_lin - K a_h^2 / (3 R).
  const double beyond = linear_force - stiffness * punch_radius * punch_radius / (3 * radius);
  if (beyond >= hertz_force_at(punch_radius, e_star, radius)) return beyond;
  // Below: h(a) = F(a) + K delta(F(a)) - F_lin rises strictly with the Hertz
  // radius a on [0, a_h] (h' = a (4 E* a / R + 2 K (1 - a / a_h) / R) > 0),
  // h(0) < 0 <= h(a_h): Newton's steps kept inside the bracket, else bisection.
  const auto h = [&](double a) {
    const double f = hertz_force_at(a, e_star, radius);
    return f + stiffness * (a * a / radius - f / (2 * e_star * punch_radius)) - linear_force;
  };
  double lo = 0, hi = punch_radius, a = punch_radius;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double value = h(a);
    if (value == 0) break;
    (value < 0 ? lo : hi) = a;
    const double slope = a * (4 * e_star * a / radius + 2 * stiffness * (1 - a / punch_radius) / radius);
    double next = slope > 0 ? a - value / slope : lo;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool settled = std::abs(next - a) <= 1e-13 * punch_radius;
    a = next;
    if (settled) break;
  }
  return hertz_force_at(a, e_star, radius);
}

}  // namespace organsim::force_law
