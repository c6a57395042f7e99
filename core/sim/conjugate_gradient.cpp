#include "core/sim/conjugate_gradient.h"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace organsim {

namespace {

// Coordinates per block: the vectors' blocks stay in L1 between the fused
// updates of one pass.
constexpr Eigen::Index kBlock = 2048;

// body(begin, end) on each block of [0, n), the blocks shared out over
// `threads`; returns the sum of body's results, added in block order.
template <class Body>
double over_blocks(Eigen::Index n, int32_t threads, std::vector<double>& partial, const Body& body) {
  const Eigen::Index blocks = (n + kBlock - 1) / kBlock;
  partial.resize(static_cast<size_t>(blocks));
  const auto block = [&](Eigen::Index k) {
    partial[static_cast<size_t>(k)] = body(k * kBlock, std::min(n, (k + 1) * kBlock));
  };
  // No region on one thread: libgomp allocates a team for every region, even of one thread.
  if (threads > 1 && !omp_in_parallel()) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (Eigen::Index k = 0; k < blocks; ++k) block(k);
  } else {
    for (Eigen::Index k = 0; k < blocks; ++k) block(k);
  }
  double sum = 0;
  for (const double s : partial) sum += s;
  return sum;
}

}  // namespace

CgResult conjugate_gradient(const LinearOperator& A, const LinearOperator& precondition, const Eigen::VectorXd& b,
                            const Eigen::VectorXd& free, double tolerance, int32_t max_iterations, Eigen::VectorXd& x,
                            CgWorkspace& work) {
  CgResult result;
  const Eigen::Index n = b.size();
  const int32_t threads = std::max<int32_t>(work.threads, 1);
  const auto blocks = [&](const auto& body) { return over_blocks(n, threads, work.partial, body); };
  Eigen::VectorXd &bf = work.b, &r = work.r, &z = work.z, &p = work.p, &q = work.q;
  x = x.cwiseProduct(free);
  bf = b.cwiseProduct(free);
  const double bnorm =
      std::sqrt(blocks([&](Eigen::Index i, Eigen::Index e) { return bf.segment(i, e - i).squaredNorm(); }));
  if (!(bnorm > 0)) {
    x.setZero();
    result.converged = true;
    return result;
  }
  q.resize(n), z.resize(n), p.resize(n), r.resize(n);
  A(x, q);
  r = bf - q.cwiseProduct(free);
  precondition(r, z);
  // z = P r on the free coordinates, rz = r . z; the same pass again in every iteration.
  const auto project_z = [&]() {
    return blocks([&](Eigen::Index i, Eigen::Index e) {
      auto zs = z.segment(i, e - i);
      zs = zs.cwiseProduct(free.segment(i, e - i));
      return r.segment(i, e - i).dot(zs);
    });
  };
  double rz = project_z();
  p = z;
  double rnorm = std::sqrt(blocks([&](Eigen::Index i, Eigen::Index e) { return r.segment(i, e - i).squaredNorm(); }));
  while (result.iterations < max_iterations && rnorm > tolerance * bnorm) {
    A(p, q);
    const double curvature = blocks([&](Eigen::Index i, Eigen::Index e) {
      auto qs = q.segment(i, e - i);
      qs = qs.cwiseProduct(free.segment(i, e - i));
      return p.segment(i, e - i).dot(qs);
    });
    if (!(curvature > 0)) break;
    const double step = rz / curvature;
    rnorm = std::sqrt(blocks([&](Eigen::Index i, Eigen::Index e) {
      x.segment(i, e - i) += step * p.segment(i, e - i);
      auto rs = r.segment(i, e - i);
      rs -= step * q.segment(i, e - i);
      return rs.squaredNorm();
    }));
    ++result.iterations;
    precondition(r, z);
    const double rz_next = project_z();
    const double ratio = rz_next / rz;
    blocks([&](Eigen::Index i, Eigen::Index e) {
      p.segment(i, e - i) = z.segment(i, e - i) + ratio * p.segment(i, e - i);
      return 0.0;
    });
    rz = rz_next;
  }
  result.residual = rnorm / bnorm;
  result.converged = rnorm <= tolerance * bnorm;
  return result;
}

}  // namespace organsim
