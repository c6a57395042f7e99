#pragma once
// Bounded nonlinear least squares without derivatives: Levenberg-Marquardt on
// a forward-difference Jacobian, for a handful of parameters whose residual
// is expensive (one simulation each). Parameters marked `log` are searched in
// log space (moduli: positive, and a factor of 3 off is as far as 1/3 off).
#include <functional>
#include <string>
#include <vector>

namespace organsim {

struct FitParameter {
  std::string name;
  double start = 0;
  double lower = 0, upper = 0;  // bounds, inclusive
  bool log = false;             // search log(value); needs lower > 0
};

struct LeastSquaresOptions {
  int32_t max_iterations = 30;       // Jacobian evaluations
  double relative_step = 1e-3;       // finite-difference step in the search coordinate
  double tolerance = 1e-6;           // stop when a step changes every search coordinate by less
};

struct LeastSquaresResult {
  std::vector<double> values;   // best parameters found
  double cost = 0;              // 1/2 sum r^2 at values
  int32_t iterations = 0;
  int32_t evaluations = 0;
  bool converged = false;       // stopped at a local minimum before max_iterations
  std::string stop_reason;
  std::vector<double> cost_history;  // after each iteration
};

// residual(values) returns the residual vector (same length every call; a
// non-finite entry marks the point as infeasible). progress(iteration, cost,
// values) is called after each iteration.
LeastSquaresResult least_squares(
    const std::vector<FitParameter>& parameters,
    const std::function<std::vector<double>(const std::vector<double>&)>& residual, const LeastSquaresOptions& options,
    const std::function<void(int32_t, double, const std::vector<double>&)>& progress = {});

}  // namespace organsim
