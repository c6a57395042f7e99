#pragma once
// The linear system of one backward (implicit) Euler step, matrix-free:
//   (M + h D + h^2 K) dv = h (f + h (-K) v)   (SOFA's one-step form),
// K = -df/dx and D = -df/dv the force law's tangent at the step's state,
// kept positive semi-definite (force_law.h, "Tangent stiffness"), so that
// preconditioned conjugate gradients solve it. Products are evaluated from
// per-element data stored at linearise() (no assembled matrix): springs
// (k - t) u u^T + t I and their dampers d u u^T, the volume term's
// Gauss-Newton part k g g^T (per tet, or G^T diag(k_a) G for the nodal term;
// the pressure's own second derivative p d^2V/dx^2 is left out: it is
// indefinite and vanishes at rest), the shear element's rest stiffness and
// its damper's (constant sparse matrices, exact at rest), the drag alpha m I,
// and the tool's contact blocks (ContactBlock). Fixed points are projected
// out by the caller (conjugate_gradient's `free`). docs/integrators.md
// derives it.
//
// Threads: products and diagonal blocks gather per point, each point's
// springs and tet corners in a fixed order (incidence lists built at
// construction), as the explicit force pass does: a spring's term is
// evaluated at both its ends, a tet's coefficient once per tet before the
// gather. So both run as OpenMP loops on any number of threads with
// bit-identical results and no per-thread buffers to sum.
//
// The product's gather runs on a SIMD target when one is given
// (core/sim/implicit_gather_simd.h: a register of points at a time, the
// same terms in the same order), else in scalar code, the reference; the two
// differ by rounding only.
#include <Eigen/SparseCore>
#include <array>
#include <optional>
#include <vector>

#include "core/model/model.h"
#include "core/sim/implicit_gather_simd.h"

namespace organsim {

// A contact's stiffness on up to three points with weights w (a triangle's
// corners; one point with w = 1 for a point contact, an attachment or a
// friction anchor): block (p_i, p_j) of K gains w_i w_j k. k symmetric
// positive semi-definite; unused corners have point -1.
struct ContactBlock {
  std::array<int32_t, 3> point{-1, -1, -1};
  std::array<double, 3> w{0, 0, 0};
  Eigen::Matrix3d k = Eigen::Matrix3d::Zero();
};

class ImplicitSystem {
 public:
  // The Model's constant parts (the shear element's rest matrices); the
  // Model must outlive the system. `threads` (>= 1) share out its loops;
  // results do not depend on it. `product`: the SIMD target of apply()'s
  // gather (one of simd_targets_supported()); none: the scalar gather.
  explicit ImplicitSystem(const Model& model, int32_t threads = 1, const std::optional<SimdTarget>& product = {});

  // The tangent at positions x and velocities v (npoint), the sutures' rest
  // lengths at time t, with the contact's blocks.
  // The blocks are copied into a vector the system keeps (no allocation
  // once it has held as many).
  void linearise(const std::vector<Vec3>& x, const std::vector<Vec3>& v, double t, const std::vector<ContactBlock>& contact);

  // out = (M m_coef + D alpha + K beta) p over all 3 npoint coordinates
  // (fixed points included: the caller projects them out).
  void apply(double m_coef, double alpha, double beta, const Eigen::VectorXd& p, Eigen::VectorXd& out) const;
  // The diagonal 3x3 blocks of the same matrix (npoint).
  void diagonal_blocks(double m_coef, double alpha, double beta, std::vector<Eigen::Matrix3d>& out) const;

  const Model& model() const { return model_; }

  using ShearMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

 private:
  // Runs body(i) for i in [0, n) as a static loop: in a parallel region of
  // threads_ threads, or on its own on one (libgomp allocates a team for
  // every region, even of one thread) or inside a caller's region.
  template <class Body>
  void for_each(int32_t n, const Body& body) const;
  // Over n items of which the first kGatherGroup x groups are whole SIMD
  // groups: simd(first, last) on blocks of groups, then scalar(i) on each
  // item past them, on for_each's threads.
  template <class Simd, class Scalar>
  void for_each_group(int32_t n, int32_t groups, const Simd& simd, const Scalar& scalar) const;

  const Model& model_;
  int32_t threads_;
  // Per spring at the linearisation: its direction, axial and transverse
  // stiffness (K = axial u u^T + transverse I) and damper (D = d u u^T); a
  // slack suture has all three zero.
  struct SpringTangent {
    Vec3 u{0, 0, 0};
    double axial = 0, transverse = 0, d = 0;
  };
  std::vector<SpringTangent> springs_;  // nspring + 1
  // Volume term: dV_t/dx_i of every tet's corners at the linearisation
  // (ntet + 1).
  std::vector<std::array<Vec3, 4>> volume_gradient_;
  // Each point's springs and tet corners, rows start[i] .. start[i + 1] in
  // element order: spring_of_point_ holds 2 s + end (0: a, 1: b) and
  // spring_other_ the spring's other end, corner_of_point_ 4 t + corner.
  std::vector<int32_t> spring_start_, spring_of_point_, spring_other_, corner_start_, corner_of_point_;
  // The same tangents in those rows' order (a spring's at both its ends),
  // so that the per-point gathers read them in sequence, not scattered
  // over all springs and tets.
  std::vector<SpringTangent> spring_at_;
  std::vector<Vec3> corner_gradient_;
  // The SIMD passes and their streams (null without a target), whose
  // tangents linearise() copies in from the slots' springs and corners
  // (spring s, corner 4 t + c; a padding slot names the zero element past
  // the last of springs_ and volume_gradient_), as it copies the tets'
  // gradients.
  const GatherKernels* simd_ = nullptr;
  GatherStreams streams_;
  std::vector<int32_t> slot_spring_, slot_corner_;
  std::vector<ContactBlock> contact_;
  // The shear element's rest stiffness and its damper's (empty without the
  // element; different matrices: the stiffness blends in the smoothed part,
  // the damper is the per-tet element's alone).
  ShearMatrix shear_k_, shear_d_;
  // beta shear_k_ + alpha shear_d_ as scale times one matrix: a single
  // one when the other coefficient is zero (a step's K v), else their sum,
  // kept for the last (alpha, beta) with both: CG applies it many times
  // with the same pair, so the sum is formed once per step size and each
  // row is one product (apply and diagonal_blocks keep scratch: one caller
  // at a time). matrix nullptr when the whole is zero.
  struct ShearRows {
    const ShearMatrix* matrix = nullptr;
    double scale = 0;
  };
  ShearRows shear_rows(double alpha, double beta) const;
  mutable ShearMatrix shear_;
  mutable double shear_alpha_ = 0, shear_beta_ = 0;
  // The volume term's per-tet and nodal scalars; tet_term_ has one more, 0:
  // the SIMD gather's padding corners read it.
  mutable std::vector<double> tet_term_, node_term_;
  // The nodal diagonal: each point's patch (the nodes sharing a tet with
  // it), rows patch_start_[i] .. patch_start_[i + 1] of patch_point_, and
  // for each of its tet corners (corner_of_point_[k]) the slot in its patch
  // of that tet's four nodes (patch_slot_[4 k + j]); per thread, the
  // patch's G rows at the point.
  std::vector<int32_t> patch_start_, patch_point_;
  std::vector<uint16_t> patch_slot_;
  mutable std::vector<std::vector<Vec3>> patch_row_;
};

}  // namespace organsim
