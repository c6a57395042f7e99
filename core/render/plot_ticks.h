#pragma once
// Axis ticks shared by the plots drawn with OpenCV (force_plot, xy_plot).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace organsim {

// Tick step of 1, 2 or 5 x 10^k giving about `target` intervals over span.
inline double nice_step(double span, int target) {
  const double raw = span / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / mag;
  const double m = r < 1.5 ? 1 : r < 3.5 ? 2 : r < 7.5 ? 5 : 10;
  return m * mag;
}

// Enough decimals to tell neighbouring ticks apart.
inline std::string tick_label(double v, double step) {
  const int decimals = std::clamp(static_cast<int>(-std::floor(std::log10(step) + 1e-9)), 0, 9);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return buf;
}

}  // namespace organsim
