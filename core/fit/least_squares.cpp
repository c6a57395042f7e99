#include "core/fit/least_squares.h"

#include <Eigen/Dense>
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
  std::vector<double> values(const Eigen::VectorXd& z) const {
    std::vector<double> v(p.size());
    for (size_t i = 0; i < p.size(); ++i) v[i] = to_value(i, z[static_cast<Eigen::Index>(i)]);
    return v;
  }
  Eigen::VectorXd clamp(Eigen::VectorXd z) const {
    for (size_t i = 0; i < p.size(); ++i) z[static_cast<Eigen::Index>(i)] = to_search(i, values(z)[i]);
    return z;
  }
};

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
  const Eigen::Index n = static_cast<Eigen::Index>(parameters.size());
  for (const FitParameter& p : parameters)
    if (!(p.lower <= p.start && p.start <= p.upper) || (p.log && !(p.lower > 0)))
      throw Error(ErrorKind::Usage, p.name + ": start " + std::to_string(p.start) + " outside its bounds [" +
                                        std::to_string(p.lower) + ", " + std::to_string(p.upper) + "]");
  const Search search{parameters};
  LeastSquaresResult result;
  Eigen::VectorXd z(n);
  for (Eigen::Index i = 0; i < n; ++i) z[i] = search.to_search(static_cast<size_t>(i), parameters[i].start);
  auto evaluate = [&](const Eigen::VectorXd& at) {
    ++result.evaluations;
    return residual(search.values(at));
  };
  std::vector<double> r = evaluate(z);
  double cost = half_squared(r);
  if (!std::isfinite(cost)) throw Error(ErrorKind::Numerical, "fit: the simulation at the start values failed");
  double lambda = 1e-3;  // Levenberg-Marquardt damping, relative to diag(J^T J)
  for (result.iterations = 0; result.iterations < options.max_iterations;) {
    // Forward-difference Jacobian in search coordinates, stepping inwards at a bound.
    const Eigen::Index m = static_cast<Eigen::Index>(r.size());
    Eigen::MatrixXd J(m, n);
    const Eigen::Map<const Eigen::VectorXd> r0(r.data(), m);
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::VectorXd step = z;
      double h = options.relative_step * std::max(1.0, std::abs(z[i]));
      if (search.to_value(static_cast<size_t>(i), z[i] + h) == search.to_value(static_cast<size_t>(i), z[i])) h = -h;
      step[i] += h;
      const std::vector<double> ri = evaluate(step);
      for (Eigen::Index k = 0; k < m; ++k) J(k, i) = (ri[k] - r[k]) / h;
    }
    ++result.iterations;
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r0;
    bool improved = false, small_step = false;
    for (int attempt = 0; attempt < 12 && !improved; ++attempt) {
      Eigen::MatrixXd A = JtJ;
      for (Eigen::Index i = 0; i < n; ++i) A(i, i) += lambda * std::max(JtJ(i, i), 1e-30);
      const Eigen::VectorXd trial = search.clamp(z - A.ldlt().solve(g));
      small_step = ((trial - z).array().abs() <= options.tolerance * (1.0 + z.array().abs())).all();
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
