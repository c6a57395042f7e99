#pragma once
// The coarse level of the implicit solve's two-level preconditioner
// (Preconditioner::TwoLevel): block Jacobi removes the error that varies
// from point to point, and a correction on a few rigid-body modes per
// aggregate of points removes the smooth error that block Jacobi leaves
// and that makes CG slow on a stiff organ (condition number ~ (h + damping
// time) h omega_max^2).
//
//   z = D^-1 r + P A_c^-1 P^T r,   A_c = P^T (M + h D_rest + beta K_rest) P
//
// (additive two-level Schwarz). The aggregates are the free points within
// two springs of a root, chosen greedily in point order over the spring
// graph; P holds each aggregate's three translations and three rotations
// about its centroid at rest, orthonormalised per aggregate (a mode an
// aggregate cannot carry, such as a rotation of collinear points, is
// dropped). The rest matrices are projected once per Model version (on the
// change worker's thread when a topology change makes a new one); the
// small A_c is factored once per step size. docs/integrators.md,
// "Preconditioners", gives its iteration counts.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cstdint>

#include "core/model/model.h"

namespace organsim {

class CoarseSpace {
 public:
  // Aggregates the free points and projects the rest matrices onto P.
  explicit CoarseSpace(const Model& model);

  // Factors A_c for this h and beta (h^2 with the stiffness in the system,
  // 0 without) unless it already is.
  void factor(double h, double beta);
  // z += P A_c^-1 P^T r over all 3 npoint coordinates (fixed ones get 0).
  // Allocates nothing once factored.
  void add_correction(const Eigen::VectorXd& r, Eigen::VectorXd& z);

  int32_t aggregates() const { return aggregates_; }
  int32_t modes() const { return static_cast<int32_t>(rc_.size()); }
  // Each point's aggregate (-1 for a fixed point).
  const std::vector<int32_t>& aggregate_of() const { return aggregate_of_; }

 private:
  int32_t aggregates_ = 0;
  std::vector<int32_t> aggregate_of_;
  // P by points: point i's rows of P are block_[i] on the columns
  // first_mode_[aggregate] on (unused columns and fixed points' rows 0).
  std::vector<Eigen::Matrix<double, 3, 6>> block_;
  std::vector<int32_t> first_mode_;
  Eigen::SparseMatrix<double> mass_, damping_, stiffness_;  // P^T M P, P^T D_rest P, P^T K_rest P
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor_;
  bool factored_ = false;
  double h_ = 0, beta_ = 0;
  Eigen::VectorXd inverse_d_, rc_, yc_, zc_;
};

}  // namespace organsim
