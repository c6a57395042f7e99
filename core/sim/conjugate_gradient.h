#pragma once
// Preconditioned conjugate gradients on the free coordinates of a symmetric
// positive (semi-)definite system: the implicit integrator's linear solve
// (core/sim/reference_backend.h).
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

namespace organsim {

// y = A x over every coordinate (a fixed one's entries are ignored).
using LinearOperator = std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& y)>;

struct CgResult {
  int32_t iterations = 0;
  double residual = 0;     // |b - A x| / |b| on the free coordinates at the end (0 when b = 0)
  bool converged = false;  // residual <= tolerance
};

// The solver's vectors, kept by the caller between solves: once sized, a
// solve allocates nothing. `threads` share out its vector updates and dot
// products; each dot product sums fixed blocks of coordinates and then the
// blocks in order, so the result does not depend on the thread count.
struct CgWorkspace {
  int32_t threads = 1;
  Eigen::VectorXd b, r, z, p, q;
  std::vector<double> partial;  // one sum per block
};

// Solves A x = b restricted to the coordinates where `free` is 1 (0: held,
// x there is set to 0 and A's rows and columns are dropped), starting from
// x's value (a warm start), with the preconditioner z = P r (an
// approximation of A^-1, symmetric positive definite). Stops when
// |b - A x| <= tolerance |b| or after max_iterations, or when A shows a
// direction of non-positive curvature (then converged is false).
CgResult conjugate_gradient(const LinearOperator& A, const LinearOperator& precondition, const Eigen::VectorXd& b,
                            const Eigen::VectorXd& free, double tolerance, int32_t max_iterations, Eigen::VectorXd& x,
                            CgWorkspace& work);

}  // namespace organsim
