#pragma once
// Small-strain static equilibrium of a Model: the stiffness of its force law
// linearised at rest (springs k u u^T, volume term k_v g_i g_j^T per tet or
// G^T diag(k_a) G nodal, shear element k_t ((g_i . g_j) I + g_j g_i^T)),
// solved directly. This is the response every backend converges to under a
// slow (quasi-static) load, without the dynamics: the validation suite uses it to
// compare the force law with elasticity theory in milliseconds.
#include <array>
#include <memory>
#include <vector>

#include "core/model/model.h"

namespace organsim {

// Displacement `value` (m) prescribed on one coordinate (0 x, 1 y, 2 z) of a
// point (internal numbering). The Model's fixed points are held at zero.
struct PrescribedDof {
  int32_t point = 0;
  int axis = 0;
  double value = 0;
};

// A one-directional spring on a point: energy k/2 (n . u - target)^2, i.e.
// force k (target - n . u) n. Models rigid frictionless contact (penalty).
struct PointSpring {
  int32_t point = 0;
  Vec3 direction{0, 0, 1};  // unit
  double k = 0;             // N/m
  double target = 0;        // m
};

// The same spring on a point of a surface triangle: energy
// k/2 (n . sum_i w_i u_i - target)^2, i.e. force w_i k (target - n . u_q) n on
// corner i, u_q the displacement of the point with barycentric weights w.
// Models the surface contact (force_law::sphere_triangle_penalty) linearised
// at fixed weights and normal.
struct SurfaceSpring {
  std::array<int32_t, 3> points{};
  std::array<double, 3> weights{};
  Vec3 direction{0, 0, 1};  // unit
  double k = 0;             // N/m
  double target = 0;        // m
};

struct StaticProblem {
  std::vector<PrescribedDof> prescribed;
  std::vector<Vec3> load;                 // external force per point, N (npoint, or empty)
  std::vector<PointSpring> point_springs;
  std::vector<SurfaceSpring> surface_springs;
};

struct StaticSolution {
  std::vector<Vec3> displacement;  // u, m (npoint)
  // Force the supports exert on each point, N (npoint): K u - load - springs'
  // force; non-zero only at prescribed coordinates.
  std::vector<Vec3> reaction;
};

// The rest stiffness factored once for one set of held coordinates (the
// Model's fixed points and the prescribed ones); it then solves any problem
// with those supports, whatever its prescribed values, loads and springs.
// The springs are rank-one terms k a a^T, added by the Woodbury identity:
// a contact iteration that changes its springs costs a back-substitution per
// spring, not a factorisation.
class StaticSolver {
 public:
  // Throws Error(Numerical) when the free part of the stiffness is singular
  // (e.g. a rigid motion left unconstrained).
  StaticSolver(const Model& model, const std::vector<PrescribedDof>& held);
  ~StaticSolver();
  StaticSolver(const StaticSolver&) = delete;
  StaticSolver& operator=(const StaticSolver&) = delete;

  // Throws Error(Usage) when `problem` holds other coordinates than the
  // solver was factored for.
  StaticSolution solve(const StaticProblem& problem) const;

  // 1/2 u^T K u, J: the rest stiffness's energy at displacements u (npoint).
  double elastic_energy(const std::vector<Vec3>& u) const;

  // K u, N (npoint): the rest stiffness's force at displacements u; at the
  // held coordinates of an equilibrium, the supports' reaction.
  std::vector<Vec3> elastic_force(const std::vector<Vec3>& u) const;

 private:
  struct Factor;
  const Model& model_;
  std::unique_ptr<Factor> factor_;
};

// One problem, one factorisation: StaticSolver(model, problem.prescribed).solve(problem).
StaticSolution solve_static(const Model& model, const StaticProblem& problem);

// The linearised stiffness's diagonal 3x3 block trace per point, N/m (npoint):
// a scale for penalty springs.
std::vector<double> stiffness_diagonal(const Model& model);

}  // namespace organsim
