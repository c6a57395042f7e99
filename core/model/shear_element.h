#pragma once
// The per-tet shear element that lets a spring lattice reach Poisson ratios
// below 1/4 (docs/physics.md). A central-force lattice has lambda = mu
// (Cauchy), so below nu = 1/4 part of the shear stiffness must come from a
// non-central term: per tet a compressible neo-Hookean energy without its
// lambda part,
//   W_t = k_t [ (|F|^2 - 3) / 2 + phi(J) ],  k_t = mu_e V_t^r,  J = det F,
// phi(J) = -ln J, on the tet's deformation gradient F = sum_i x_i g_i^T (g_i
// the rest gradients of the tet's barycentric coordinates, sum g_i = 0).
// It depends on F only through F^T F and J, so a rigidly rotated tet has no
// force and no polar decomposition is needed; at small strain
// W_t = mu_e V |eps|^2, the energy of a linear solid with Lame constants
// (lambda, mu) = (0, mu_e). -ln J grows without bound as a tet is crushed,
// so the element resists compression all the way (a St Venant-Kirchhoff
// energy on the Green strain, which also has that small-strain limit,
// softens beyond 42 % shortening and is zero again for an inverted copy of
// the rest shape: a liver at nu = 0 collapsed under its own weight with it).
// Below J = kShearElementMinJ, phi continues as its quadratic Taylor
// expansion there, so energy and force stay finite for any J and keep
// pushing an inverted tet (J <= 0) back. The force on vertex i is
// f_i = -dW/dx_i = -k_t (F + phi'(J) cof F) g_i, cof F = J F^-T.
//
// Its damper (Kelvin-Voigt, docs/physics.md): a viscous Cauchy stress
// 2 mu_e tau D with the rate of deformation D = sym(Fdot F^-1), Fdot =
// sum_i v_i g_i^T, and tau = Model::shear_damping_time. As a force,
//   f_i = -(2 tau k_t / J_d) sym(Fdot cof(F)^T) cof(F) g_i,  J_d = max(J, J_min),
// which is exactly -V sigma grad_x N_i for J >= J_min. At rest (F = I) it is
// -tau K v with K the element's stiffness, as a spring's damper is tau times
// its stiffness; a rigid rotation has Fdot cof^T = J W (W skew), so no
// force; and its power is -2 tau k_t J_d |D_d|^2 <= 0 for any F (D_d =
// sym(Fdot cof^T) / J_d), an inverted tet included. J_d stops the 1/J
// growth where the barrier hands over to its quadratic extension, so the
// damper's stiffness, like the barrier's, stays within a few times its rest
// value and the damped dt_crit stays meaningful.
//
// Smoothed (Model::shear_smoothed_share s > 0, the default): a constant-strain
// tet cannot bend, so with 2-3 cells through a part's thickness the element
// above is 13-35 % too stiff in bending (docs/validation.md); gradients
// averaged over node patches (node-based smoothed FEM, Liu et al.) are too
// soft instead. The energy is split between the two:
//   W = sum_t (1 - s) k_t psi(F_t) + sum_a s (K_a / 4) psi(Fbar_a),
//   Fbar_a = I + sum over the tets t of a of k_t (F_t - I) / K_a,
// psi(F) = (|F|^2 - 3) / 2 + phi(J), K_a = sum of k_t over the tets of a
// (Model::point_shear_k; K_a / 4 = mu_e V_a, V_a the nodal volume). The
// force on corner i of tet t is
//   f_i = -k_t [(1 - s) P(F_t) + s Pbar_t] g_i,  P(F) = F + phi'(J) cof F,
// Pbar_t the mean of P(Fbar_a) over t's four corners. Both parts are
// functions of F^T F and J, so rotations stay force-free. The damper is the
// per-tet one above with the full k_t (its rest matrix is tau times the
// per-tet element's stiffness, not the blend's).
//
// The element's stress, barrier and damper are core/physics/force_law.h;
// this file evaluates them over a Model in double precision outside the
// kernels (reference forces, energy, rest stiffness).
#include <array>
#include <vector>

#include "core/model/model.h"
#include "core/physics/force_law.h"

namespace organsim {

// Rest gradients g_i of the barycentric coordinates of the tet (x0..x3),
// 1/m: g_i = (dV/dx_i) / V. They sum to zero.
std::array<Vec3, 4> shape_gradients(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

// g of `point`, one of tet t's corners (the gathered kernels store the
// gradients of a slot's other three corners).
const Vec3& shape_gradient_of(const Model& model, int32_t t, int32_t point);

// F = sum_i x_i g_i^T of tet t at positions x (internal numbering).
Eigen::Matrix3d deformation_gradient(const Model& model, int32_t t, const std::vector<Vec3>& x);

// Sum over the tets of W_t, J; 0 without the element.
double shear_element_energy(const Model& model, const std::vector<Vec3>& x);

// Adds f_i = -k_t (F + phi'(J) cof F) g_i of every tet into force (npoint);
// nothing without the element.
void add_shear_element_forces(const Model& model, const std::vector<Vec3>& x, std::vector<Vec3>& force);

// Adds the damper's f_i = -(2 tau k_t / J_d) sym(Fdot cof^T) cof g_i of every
// tet at positions x and velocities v into force (npoint); nothing without
// the element or with tau = 0.
void add_shear_element_damping_forces(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                                      std::vector<Vec3>& force);

// P(Fbar_a) of every point at positions x (npoint; zero where K_a = 0 or
// without the smoothed part).
std::vector<Eigen::Matrix3d> smoothed_shear_stress(const Model& model, const std::vector<Vec3>& x);

// Block (i, j) of the per-tet element's stiffness at rest, N/m, for corners
// i, j of tet t: k_t ((g_i . g_j) I + g_j g_i^T), the linear solid with
// lambda = 0. With a smoothed share s the elastic stiffness is (1 - s) times
// these blocks plus the patches below; the damper's is tau times these.
Eigen::Matrix3d shear_element_rest_block(const Model& model, int32_t t, int i, int j);

// The smoothed part's rest stiffness, node patch by node patch: for point a,
// each point p of its tets with w_ap = sum over the tets t of a holding p of
// k_t g_tp / K_a. Node a adds s (K_a / 4) ((w_ap . w_aq) I + w_aq w_ap^T) to
// block (p, q). Empty where K_a = 0.
struct ShearPatchEntry {
  int32_t point = 0;
  Vec3 w{0, 0, 0};  // 1/m
};
std::vector<ShearPatchEntry> smoothed_shear_patch(const Model& model, int32_t a);

// The weight s K_a / 4 of node a's patch blocks, J (times w w^T in 1/m^2: N/m).
inline double smoothed_shear_patch_k(const Model& model, int32_t a) {
  return model.shear_smoothed_share * model.point_shear_k[a] / 4;
}

}  // namespace organsim
