#include "core/sim/conjugate_gradient.h"

namespace organsim {

CgResult conjugate_gradient(const LinearOperator& A, const LinearOperator& precondition, const Eigen::VectorXd& b,
                            const Eigen::VectorXd& free, double tolerance, int32_t max_iterations, Eigen::VectorXd& x,
                            CgWorkspace& work) {
  CgResult result;
  x = x.cwiseProduct(free);
  Eigen::VectorXd &bf = work.b, &r = work.r, &z = work.z, &p = work.p, &q = work.q;
  bf = b.cwiseProduct(free);
  const double bnorm = bf.norm();
  if (!(bnorm > 0)) {
    x.setZero();
    result.converged = true;
    return result;
  }
  q.resize(x.size()), z.resize(x.size());
  A(x, q);
  r = bf - q.cwiseProduct(free);
  precondition(r, z);
  z = z.cwiseProduct(free);
  p = z;
  double rz = r.dot(z);
  double rnorm = r.norm();
  while (result.iterations < max_iterations && rnorm > tolerance * bnorm) {
    A(p, q);
    q = q.cwiseProduct(free);
    const double curvature = p.dot(q);
    if (!(curvature > 0)) break;
    const double step = rz / curvature;
    x += step * p;
    r -= step * q;
    ++result.iterations;
    rnorm = r.norm();
    precondition(r, z);
    z = z.cwiseProduct(free);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  result.residual = rnorm / bnorm;
  result.converged = rnorm <= tolerance * bnorm;
  return result;
}

}  // namespace organsim
