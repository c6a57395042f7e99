// One spring, one mass: period, amplitude and damping against the analytic
// solution of m x'' + d x' + k x = 0.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/sim/cpu_backend.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace spring_mass_test {
namespace {

struct Oscillation {
  std::vector<double> t, x;  // displacement along the spring, m
};

// Mass at (0,0,-rest-amplitude) below a fixed point, released at rest.
Oscillation simulate(double k, double m, double d, double amplitude, double dt, double duration) {
  const double rest = 0.1;
  Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0, 0, -rest)}, {m, m}, {{0, 1}}, k, d, {0});
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  const std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(0, 0, -rest - amplitude)};
  backend->set_state(x, x);
  Oscillation out;
  std::vector<Vec3> pos;
  TickRequest request;
  request.dt = dt;
  request.substeps = 1;
  const int steps = static_cast<int>(std::round(duration / dt));
  for (int i = 0; i < steps; ++i) {
    backend->tick(request);
    backend->positions(pos);
    out.t.push_back(backend->time());
    out.x.push_back(-pos[1].z() - rest);
  }
  return out;
}

// Times where x crosses zero going up, linearly interpolated.
std::vector<double> upward_crossings(const Oscillation& o) {
  std::vector<double> times;
  for (size_t i = 1; i < o.x.size(); ++i)
    if (o.x[i - 1] < 0 && o.x[i] >= 0)
      times.push_back(o.t[i - 1] + (o.t[i] - o.t[i - 1]) * (-o.x[i - 1]) / (o.x[i] - o.x[i - 1]));
  return times;
}

TEST(SpringMass, UndampedPeriodAndAmplitude) {
  const double k = 10, m = 0.01, amplitude = 0.01;
  const double omega = std::sqrt(k / m), period = 2 * std::numbers::pi / omega;
  // dt = T/2000: Verlet's phase error (omega dt)^2/24 ~ 4e-7 relative.
  const Oscillation o = simulate(k, m, 0, amplitude, period / 2000, 3.2 * period);
  const auto crossings = upward_crossings(o);
  ASSERT_GE(crossings.size(), 3u);
  const double measured = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  EXPECT_NEAR(measured, period, 1e-4 * period);  // 1e-4: crossing interpolation + phase error, with margin
  double max_abs = 0;
  for (double v : o.x) max_abs = std::max(max_abs, std::abs(v));
  EXPECT_NEAR(max_abs, amplitude, 1e-4 * amplitude);  // no numerical damping or growth
}

TEST(SpringMass, DampedDecayAndPeriod) {
  const double k = 10, m = 0.01, d = 0.05, amplitude = 0.01;
  const double omega = std::sqrt(k / m);
  const double zeta = d / (2 * std::sqrt(k * m));  // ~0.079
  const double omega_d = omega * std::sqrt(1 - zeta * zeta);
  const double period_d = 2 * std::numbers::pi / omega_d;
  const Oscillation o = simulate(k, m, d, amplitude, period_d / 4000, 4.5 * period_d);
  const auto crossings = upward_crossings(o);
  ASSERT_GE(crossings.size(), 3u);
  const double measured = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  EXPECT_NEAR(measured, period_d, 2e-3 * period_d);
  // Peak amplitudes decay as exp(-zeta omega t). The damper uses the backward
  // velocity (x_t - x_{t-1})/dt, an O(omega dt) ~ 1.6e-3 relative lag: 1 % tolerance.
  std::vector<double> peak_t, peak_x;
  for (size_t i = 1; i + 1 < o.x.size(); ++i)
    if (o.x[i] > o.x[i - 1] && o.x[i] >= o.x[i + 1] && o.x[i] > 0) {
      peak_t.push_back(o.t[i]);
      peak_x.push_back(o.x[i]);
    }
  ASSERT_GE(peak_x.size(), 3u);
  const double decay = std::log(peak_x.front() / peak_x.back()) / (peak_t.back() - peak_t.front());
  EXPECT_NEAR(decay, zeta * omega, 0.01 * zeta * omega);
}

TEST(SpringMass, ViscousDragDecaysAtHalfAlpha) {
  // F = -alpha m v gives an envelope exp(-alpha t / 2).
  const double k = 10, m = 0.01, alpha = 4.0, rest = 0.1, amplitude = 0.01;
  Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0, 0, -rest)}, {m, m}, {{0, 1}}, k, 0, {0});
  model.viscous_damping = alpha;
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  const std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(0, 0, -rest - amplitude)};
  backend->set_state(x, x);
  const double period = 2 * std::numbers::pi / std::sqrt(k / m);
  const double dt = period / 4000;
  testing::run_ticks(*backend, 1, dt, static_cast<int>(std::round(4 * period / dt)));
  // After exactly 4 undamped periods (damped period differs by 0.2 %) the
  // displacement is near a peak: compare with the envelope, 1 % tolerance.
  std::vector<Vec3> pos;
  backend->positions(pos);
  const double x_end = -pos[1].z() - rest;
  EXPECT_NEAR(x_end, amplitude * std::exp(-alpha * backend->time() / 2), 0.01 * amplitude);
}

TEST(SpringMass, CoincidentPointsGiveNoNaN) {
  // A spring whose ends coincide has no direction: it must give no force, not NaN.
  Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0, 0, 0.1)}, {1, 1}, {{0, 1}}, 10, 0.1, {});
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  const std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(0, 0, 0)};
  backend->set_state(x, x);
  testing::run_ticks(*backend, 10, 1e-3, 1);
  std::vector<Vec3> pos;
  backend->positions(pos);
  for (const Vec3& p : pos) EXPECT_TRUE(p.allFinite());
}

}  // namespace
}  // namespace spring_mass_test
}  // namespace organsim
