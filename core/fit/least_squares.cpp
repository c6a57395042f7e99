#include "core/fit/least_squares.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace organsim {

namespace {

struct Search {
  const std::vector<FitParameter>& p;
  double to_search(size_t i, double v) const { return p[i].log ? std::log(v) : v; }
  double to_value(size_t i, double z) const {
    const double v = p[i].log ? std::exp(z) : z;
    return std::clamp(v, p[i].lower, p[i].upper);
  }
  std::vector<double> values(const std::vector<double>& z) const {
    std::vector<double> v(p.size());
    for (size_t i = 0; i < p.size(); ++i) v[i] = to_value(i, z[i]);
    return v;
  }
  std::vector<double> clamp(std::vector<double> z) const {
    const std::vector<double> v = values(z);
    for (size_t i = 0; i < p.size(); ++i) z[i] = to_search(i, v[i]);
    return z;
  }
};

// Solves A x = b for a small symmetric positive definite A (n x n, row-major)
// by Cholesky; false when A is not positive definite.
bool cholesky_solve(std::vector<double> A, std::vector<double>& x, size_t n) {
  for (size_t j = 0; j < n; ++j) {
    double d = A[j * n + j];
    for (size_t k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
    if (!(d > 0)) return false;
    A[j * n + j] = std::sqrt(d);
    for (size_t i = j + 1; i < n; ++i) {
      double s = A[i * n + j];
      for (size_t k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = s / A[j * n + j];
    }
  }
  for (size_t i = 0; i < n; ++i) {  // L y = b
    for (size_t k = 0; k < i; ++k) x[i] -= A[i * n + k] * x[k];
    x[i] /= A[i * n + i];
  }
  for (size_t i = n; i-- > 0;) {  // L^T x = y
    for (size_t k = i + 1; k < n; ++k) x[i] -= A[k * n + i] * x[k];
    x[i] /= A[i * n + i];
  }
  return true;
}

double half_squared(const std::vector<double>& r) {
  double s = 0;
  for (double v : r) s += v * v;
  return std::isfinite(s) ? 0.5 * s : INFINITY;
}

}  // namespace

LeastSquaresResult least_squares(
    const std::vector<FitParameter>& parameters,
    const std::function<std::vector<double>(const std::vector<double>&)>& residual, const LeastSquaresOptions& options,
    const std::function<void(int32_t, double, const std::vector<double>&)>& progress) {
  const size_t n = parameters.size();
  for (const FitParameter& p : parameters)
    if (!(p.lower <= p.start && p.start <= p.upper) || (p.log && !(p.lower > 0)))
      throw Error(ErrorKind::Usage, p.name + ": start " + std::to_string(p.start) + " outside its bounds [" +
                                        std::to_string(p.lower) + ", " + std::to_string(p.upper) + "]");
  const Search search{parameters};
  LeastSquaresResult result;
  std::vector<double> z(n);
  for (size_t i = 0; i < n; ++i) z[i] = search.to_search(i, parameters[i].start);
  auto evaluate = [&](const std::vector<double>& at) {
    ++result.evaluations;
    return residual(search.values(at));
  };
  std::vector<double> r = evaluate(z);
  double cost = half_squared(r);
  if (!std::isfinite(cost)) throw Error(ErrorKind::Numerical, "fit: the simulation at the start values failed");
  double lambda = 1e-3;  // Levenberg-Marquardt damping, relative to diag(J^T J)
  while (result.iterations < options.max_iterations) {
    // Forward-difference Jacobian in search coordinates, stepping inwards at a bound.
    const size_t m = r.size();
    std::vector<std::vector<double>> J(n, std::vector<double>(m));  // columns
    for (size_t i = 0; i < n; ++i) {
      std::vector<double> step = z;
      double h = options.relative_step * std::max(1.0, std::abs(z[i]));
      if (search.to_value(i, z[i] + h) == search.to_value(i, z[i])) h = -h;
      step[i] += h;
      const std::vector<double> ri = evaluate(step);
      for (size_t k = 0; k < m; ++k) J[i][k] = (ri[k] - r[k]) / h;
    }
    ++result.iterations;
    std::vector<double> JtJ(n * n, 0.0), g(n, 0.0);
    for (size_t i = 0; i < n; ++i) {
      for (size_t k = 0; k < m; ++k) g[i] += J[i][k] * r[k];
      for (size_t j = 0; j < n; ++j)
        for (size_t k = 0; k < m; ++k) JtJ[i * n + j] += J[i][k] * J[j][k];
    }
    bool improved = false, small_step = false;
    for (int attempt = 0; attempt < 12 && !improved; ++attempt) {
      std::vector<double> A = JtJ, delta = g;
      for (size_t i = 0; i < n; ++i) A[i * n + i] += lambda * std::max(JtJ[i * n + i], 1e-30);
      if (!cholesky_solve(A, delta, n)) {
        lambda *= 10;
        continue;
      }
      std::vector<double> trial = z;
      for (size_t i = 0; i < n; ++i) trial[i] -= delta[i];
      trial = search.clamp(trial);
      small_step = true;
      for (size_t i = 0; i < n; ++i)
        small_step = small_step && std::abs(trial[i] - z[i]) <= options.tolerance * (1.0 + std::abs(z[i]));
      if (small_step) break;
      const std::vector<double> rt = evaluate(trial);
      const double c = half_squared(rt);
      if (c < cost) {
        z = trial, r = rt, cost = c;
        lambda = std::max(lambda / 10, 1e-12);
        improved = true;
      } else {
        lambda *= 10;
      }
    }
    result.cost_history.push_back(cost);
    if (progress) progress(result.iterations, cost, search.values(z));
    if (small_step || !improved) {
      // Either way no better point is within reach of the local model.
      result.converged = true;
      result.stop_reason = small_step ? "step below tolerance" : "no step lowers the cost";
      break;
    }
  }
  if (!result.converged) result.stop_reason = "max_iterations reached";
  result.values = search.values(z);
  result.cost = cost;
  return result;
}

}  // namespace organsim
