#include "core/physics/force_law.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace organsim::force_law {

double shear_barrier(double J) {
  const double jm = kShearElementMinJ;
  if (J >= jm) return -std::log(J);
  return -std::log(jm) - (J - jm) / jm + (J - jm) * (J - jm) / (2 * jm * jm);
}

namespace {
// The Hertz force at contact radius a: 4 E* a^3 / (3 R).
double hertz_force_at(double a, double e_star, double radius) { return 4 * e_star * a * a * a / (3 * radius); }

// The offset held beyond the largest Hertz radius min(a_h, R / 2).
double hertz_layer_held(double radius, double punch_radius) {
  const double limit = kLayerContactLimit * radius;
  if (punch_radius <= limit) return punch_radius * punch_radius / (3 * radius);
  return hertz_layer_offset_at(limit, radius, punch_radius);
}
}  // namespace

double hertz_layer_offset(double force, double e_star, double radius, double punch_radius) {
  if (!(force > 0)) return 0;
  const double a = std::cbrt(3 * force * radius / (4 * e_star));
  if (a >= std::min(punch_radius, kLayerContactLimit * radius)) return hertz_layer_held(radius, punch_radius);
  return a * a / radius - force / (2 * e_star * punch_radius);
}

double line_layer_offset(double force_per_length, double e_star, double radius, double half_width) {
  if (!(force_per_length > 0)) return 0;
  const double b = std::sqrt(4 * force_per_length * radius / (std::numbers::pi * e_star));
  const double limit = kLayerContactLimit * radius;
  if (b >= half_width && half_width <= limit) return half_width * half_width / (4 * radius);
  const double held = std::min(b, limit);  // a shaft narrower than the cells: held at b = R / 2
  return held * held / (2 * radius) * (std::log(half_width / held) + 0.5);
}

double HertzLayer::linear_direction(double n[3]) const {
  double sum[3] = {0, 0, 0};
  for (const Touch& t : touches_)
    for (int i = 0; i < 3; ++i) sum[i] += t.f[i];
  const double linear = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
  for (int i = 0; i < 3; ++i) n[i] = linear > 0 ? sum[i] / linear : 0;
  return linear;
}

double HertzLayer::measure_cosines() {
  double n[3];
  const double linear = linear_direction(n);
  for (Touch& t : touches_) t.c = t.m > 0 ? (t.f[0] * n[0] + t.f[1] * n[1] + t.f[2] * n[2]) / t.m : 0;
  return linear;
}

double HertzLayer::contact_length() const {
  double n[3];
  if (!(linear_direction(n) > 0)) return 0;
  // Places relative to the first pressing touch's, so that equal places
  // give a spread of exactly 0 (a sphere, a capsule on either end).
  double weight = 0, first = 0, mean = 0;
  for (const Touch& t : touches_) {
    const double w = std::max(0.0, t.f[0] * n[0] + t.f[1] * n[1] + t.f[2] * n[2]);
    if (!(w > 0)) continue;
    if (weight == 0) first = t.s;
    weight += w, mean += w * (t.s - first);
  }
  if (!(weight > 0)) return 0;
  mean /= weight;
  double variance = 0;
  for (const Touch& t : touches_) {
    const double w = std::max(0.0, t.f[0] * n[0] + t.f[1] * n[1] + t.f[2] * n[2]);
    const double d = t.s - first - mean;
    variance += w * d * d;
  }
  variance /= weight;
  return variance > 0 ? std::sqrt(12 * variance) : 0;
}

double HertzLayer::share_of(double length) const {
  return length > 0 ? std::min(1.0, length / (2 * punch_radius())) : 0;
}

double HertzLayer::line_share() const { return share_of(contact_length()); }

double HertzLayer::offset_at(double force, double radius, double length, double beta) const {
  const double sphere = beta < 1 ? hertz_layer_offset(force, e_star(), radius, punch_radius()) : 0;
  const double line = beta > 0 ? line_layer_offset(force / length, e_star(), radius, line_half_width()) : 0;
  return (1 - beta) * sphere + beta * line;
}

double HertzLayer::offset_for(double force, double radius) const {
  if (!touching()) return 0;
  const double length = contact_length();
  return offset_at(force, radius, length, share_of(length));
}

void HertzLayer::add_touch(const double f[3], double k_t, double punch_radius, double triangle_e_star, double along) {
  Touch t;
  for (int i = 0; i < 3; ++i) t.f[i] = f[i];
  t.m = std::sqrt(t.f[0] * t.f[0] + t.f[1] * t.f[1] + t.f[2] * t.f[2]);
  t.k = k_t;
  t.s = along;
  touches_.push_back(t);
  weight_ += t.m, punch_ += t.m * punch_radius, e_star_ += t.m * triangle_e_star;
}

double HertzLayer::factor(size_t i) const {
  return hertz_layer_factor(touches_[i].m, touches_[i].k, touches_[i].c, delta_);
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
  const double length = contact_length(), beta = share_of(length);
  if (beta == 0) return solve_sphere(radius);
  delta_ = 0;
  const double linear = measure_cosines();
  if (!(linear > 0)) return;
  const auto offset = [&](double force) { return offset_at(force, radius, length, beta); };
  // h(F) = F - G(delta(F)) rises strictly with F (delta rises, G falls),
  // h(0) = -|F_lin| < 0 <= h(|F_lin|) (G <= G(0) = |F_lin|): regula falsi
  // (Illinois) on the force, to 1e-12 of itself (most penalties may be
  // lifted off, the root far below |F_lin|). delta's slope is
  // unbounded at F = 0 (like F^(2/3) or P ln P), which Newton's steps on F
  // would not survive.
  double lo = 0, hi = linear, h_lo = -linear, h_hi = linear - force_along(offset(linear));
  double force = h_hi <= 0 ? linear : lo;
  for (int iteration = 0; iteration < 200 && h_hi > 0 && hi - lo > 1e-12 * hi; ++iteration) {
    force = hi - h_hi * (hi - lo) / (h_hi - h_lo);
    if (!(force > lo && force < hi)) force = 0.5 * (lo + hi);
    const double h = force - force_along(offset(force));
    if (h == 0) break;
    if (h < 0) {
      lo = force, h_lo = h, h_hi /= 2;
    } else {
      hi = force, h_hi = h, h_lo /= 2;
    }
  }
  delta_ = offset(force);
}

void HertzLayer::solve_sphere(double radius) {
  delta_ = 0;
  if (!(measure_cosines() > 0) || !(weight_ > 0)) return;
  const double e_star = this->e_star(), a_h = punch_radius(), a_max = std::min(a_h, kLayerContactLimit * radius);
  // Beyond min(a_h, R / 2) the offset is constant.
  const double beyond = hertz_layer_held(radius, a_h);
  if (force_along(beyond) >= hertz_force_at(a_max, e_star, radius)) {
    delta_ = beyond;
    return;
  }
  // Below: h(a) = F(a) - G(delta(a)) rises strictly with the Hertz radius a
  // on [0, a_max] (F' = 4 E* a^2 / R, delta' = 2 a (1 - a / a_h) / R >= 0, G
  // falling), h(0) = -|F_lin| < 0 < h(a_max).
  const auto delta_at = [&](double a) { return hertz_layer_offset_at(a, radius, a_h); };
  double lo = 0, hi = a_max, a = a_max;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double d = delta_at(a), value = hertz_force_at(a, e_star, radius) - force_along(d);
    if (value == 0) break;
    (value < 0 ? lo : hi) = a;
    const double slope = 4 * e_star * a * a / radius + stiffness_along(d) * 2 * a * (1 - a / a_h) / radius;
    double next = slope > 0 ? a - value / slope : lo;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool settled = std::abs(next - a) <= 1e-13 * a_max;
    a = next;
    if (settled) break;
  }
  delta_ = delta_at(a);
}

}  // namespace organsim::force_law
