#include "core/sim/coarse_space.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "core/model/rest_stiffness.h"
#include "core/util/error.h"

namespace organsim {

namespace {

// A mode whose share of its aggregate's largest (by the local Gram
// matrix's eigenvalue) is below this is one the points cannot carry.
constexpr double kModeFloor = 1e-9;

// The free points of `model` in aggregates: roots taken in point order
// where no neighbour is yet taken, each with its free points within two
// springs; then every point left joins a neighbour's aggregate, and one
// with no aggregated neighbour (no springs to a free point) is its own.
std::vector<int32_t> aggregate(const Model& model, int32_t& count) {
  const int32_t n = model.npoint();
  std::vector<int32_t> start(n + 1, 0), neighbour;
  for (const auto& [a, b] : model.spring_ends) ++start[a + 1], ++start[b + 1];
  for (int32_t i = 0; i < n; ++i) start[i + 1] += start[i];
  neighbour.resize(static_cast<size_t>(start[n]));
  std::vector<int32_t> fill(start.begin(), start.end() - 1);
  for (const auto& [a, b] : model.spring_ends) neighbour[fill[a]++] = b, neighbour[fill[b]++] = a;
  std::vector<int32_t> of(n, -1);
  const auto open = [&](int32_t p) { return !model.fixed[p] && of[p] < 0; };
  count = 0;
  for (int32_t i = 0; i < n; ++i) {
    if (!open(i)) continue;
    bool clear = true;
    for (int32_t k = start[i]; k < start[i + 1] && clear; ++k) clear = model.fixed[neighbour[k]] || of[neighbour[k]] < 0;
    if (!clear) continue;
    of[i] = count;
    for (int32_t k = start[i]; k < start[i + 1]; ++k) {
      const int32_t j = neighbour[k];
      if (open(j)) of[j] = count;
      if (of[j] != count) continue;
      for (int32_t l = start[j]; l < start[j + 1]; ++l)
        if (open(neighbour[l])) of[neighbour[l]] = count;
    }
    ++count;
  }
  for (bool joined = true; joined;) {
    joined = false;
    for (int32_t i = 0; i < n; ++i) {
      if (!open(i)) continue;
      for (int32_t k = start[i]; k < start[i + 1]; ++k)
        if (!model.fixed[neighbour[k]] && of[neighbour[k]] >= 0) {
          of[i] = of[neighbour[k]], joined = true;
          break;
        }
    }
  }
  for (int32_t i = 0; i < n; ++i)
    if (open(i)) of[i] = count++;
  return of;
}

Eigen::SparseMatrix<double> project(const Eigen::SparseMatrix<double>& p, const Eigen::SparseMatrix<double>& a) {
  return Eigen::SparseMatrix<double>(p.transpose() * (a * p));
}

}  // namespace

CoarseSpace::CoarseSpace(const Model& model) {
  const int32_t n = model.npoint();
  aggregate_of_ = aggregate(model, aggregates_);
  std::vector<int32_t> start(aggregates_ + 1, 0), member(static_cast<size_t>(n));
  for (int32_t i = 0; i < n; ++i)
    if (aggregate_of_[i] >= 0) ++start[aggregate_of_[i] + 1];
  for (int32_t a = 0; a < aggregates_; ++a) start[a + 1] += start[a];
  std::vector<int32_t> fill(start.begin(), start.end() - 1);
  for (int32_t i = 0; i < n; ++i)
    if (aggregate_of_[i] >= 0) member[fill[aggregate_of_[i]]++] = i;
  // Each aggregate's six rigid modes on its points, orthonormalised through
  // the eigenvectors of their Gram matrix.
  std::vector<Eigen::Triplet<double>> entries;
  block_.assign(n, Eigen::Matrix<double, 3, 6>::Zero());
  first_mode_.resize(aggregates_);
  int32_t column = 0;
  for (int32_t a = 0; a < aggregates_; ++a) {
    first_mode_[a] = column;
    const int32_t size = start[a + 1] - start[a];
    Vec3 centre = Vec3::Zero();
    for (int32_t k = start[a]; k < start[a + 1]; ++k) centre += model.rest_position[member[k]];
    centre /= size;
    Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(3 * size, 6);
    for (int32_t k = 0; k < size; ++k) {
      const Vec3 r = model.rest_position[member[start[a] + k]] - centre;
      modes.block<3, 3>(3 * k, 0).setIdentity();
      for (int axis = 0; axis < 3; ++axis) modes.block<3, 1>(3 * k, 3 + axis) = Vec3::Unit(axis).cross(r);
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> gram(modes.transpose() * modes);
    const double largest = gram.eigenvalues().maxCoeff();
    for (int m = 0; m < 6; ++m) {
      const double lambda = gram.eigenvalues()[m];
      if (!(lambda > kModeFloor * largest)) continue;
      const Eigen::VectorXd basis = modes * gram.eigenvectors().col(m) / std::sqrt(lambda);
      for (int32_t k = 0; k < size; ++k) {
        const int32_t point = member[start[a] + k];
        block_[point].col(column - first_mode_[a]) = basis.segment<3>(3 * k);
        for (int c = 0; c < 3; ++c) entries.emplace_back(3 * point + c, column, basis[3 * k + c]);
      }
      ++column;
    }
  }
  Eigen::SparseMatrix<double> prolongation(3 * n, column);
  prolongation.setFromTriplets(entries.begin(), entries.end());
  mass_ = project(prolongation, assemble(model, lumped_mass(model)));
  damping_ = project(prolongation, assemble(model, rest_damping(model)));
  stiffness_ = project(prolongation, assemble(model, rest_stiffness(model)));
  rc_.resize(column), yc_.resize(column), zc_.resize(column);
}

void CoarseSpace::factor(double h, double beta) {
  if (factored_ && h == h_ && beta == beta_) return;
  const Eigen::SparseMatrix<double> system = mass_ + h * damping_ + beta * stiffness_;
  factor_.compute(system);
  if (factor_.info() != Eigen::Success)
    throw Error(ErrorKind::Numerical, "implicit Euler: the two-level preconditioner's coarse system (" +
                                          std::to_string(modes()) + " modes) could not be factored");
  inverse_d_ = factor_.vectorD().cwiseInverse();
  factored_ = true, h_ = h, beta_ = beta;
}

void CoarseSpace::add_correction(const Eigen::VectorXd& r, Eigen::VectorXd& z) {
  if (modes() == 0) return;
  // factor_.solve() written out as Eigen's own steps, allocating nothing
  // (solve() evaluates into a temporary, vectorD() returns a copy).
  // P^T r and P zc point by point: a point's rows touch only its
  // aggregate's (at most six) columns, so both are one pass.
  const auto modes_of = [this](int32_t a) {
    return (a + 1 < aggregates_ ? first_mode_[a + 1] : modes()) - first_mode_[a];
  };
  rc_.setZero();
  const int32_t n = static_cast<int32_t>(aggregate_of_.size());
  for (int32_t i = 0; i < n; ++i) {
    const int32_t a = aggregate_of_[i];
    if (a < 0) continue;
    const Eigen::Matrix<double, 6, 1> y = block_[i].transpose() * r.segment<3>(3 * static_cast<Eigen::Index>(i));
    rc_.segment(first_mode_[a], modes_of(a)) += y.head(modes_of(a));
  }
  yc_.noalias() = factor_.permutationP() * rc_;
  factor_.matrixL().solveInPlace(yc_);
  yc_.array() *= inverse_d_.array();
  factor_.matrixU().solveInPlace(yc_);
  zc_.noalias() = factor_.permutationPinv() * yc_;
  for (int32_t i = 0; i < n; ++i) {
    const int32_t a = aggregate_of_[i];
    if (a < 0) continue;
    const int32_t count = modes_of(a);
    Eigen::Matrix<double, 6, 1> c = Eigen::Matrix<double, 6, 1>::Zero();
    c.head(count) = zc_.segment(first_mode_[a], count);
    z.segment<3>(3 * static_cast<Eigen::Index>(i)) += block_[i] * c;
  }
}

}  // namespace organsim
