#pragma once
// Guaranteed upper bounds on the eigenvalues of M^-1 K at rest, point by
// point, so that a topology change can recompute only the rows it touched.
//
// M^-1 K has the eigenvalues of the symmetric W = M^-1/2 K M^-1/2 over the
// free points. K is a sum of positive semi-definite element matrices K_e
// (a spring, a tet's volume term, a node's nodal volume term, a tet's shear
// element, a node's smoothed shear patch), and every such K_e is bounded by
// its own diagonal blocks: for any positive tau_c over the element's free
// points c (Cauchy-Schwarz on each of its squared linear forms),
//   x^T K_e x <= sum_c (T_e / tau_c) x_c^T K_e,cc x_c,  T_e = sum_c tau_c.
// Summed over the elements, K <= blockdiag(A_i) with
//   A_i = sum_{e holding i} (T_e / tau_ei) K_e,ii,
// so lambda_max(W) <= max_i lambda_max(A_i) / m_i: the point's row (with the
// tool's k_c I added to A_i). organsim takes tau_ec = mu_ec d_c / sqrt(m_c),
// mu_ec = sqrt(lambda_max(K_e,cc)), and d the per-point scale: then
// lambda_max(A_i) / m_i <= (B d)_i / d_i with the scalar matrix
// B_ij = sum_e mu_ei mu_ej / sqrt(m_i m_j), whose Perron vector makes every
// row rho(B) (power iterations on B give d; any positive d is a proof,
// an approximate Perron vector only a looser one). With d = 1 the scalar
// form is the block Gershgorin row of W (lambda_max(K_ii) + sum_j ||K_ij||
// sqrt(m_i / m_j)) / m_i with ||K_ij|| bounded by its elements' terms, so
// the rows are never above the block Gershgorin bound; keeping A_i a matrix
// lets the directions of a point's springs and faces share the bound instead
// of adding up. On the paper's 7656-point liver (poisson_ratio 0.45, the
// tool on 905 points) the bound is 1.9 lambda_max, where the block
// Gershgorin rows gave 3.1 (docs/stability.md).
#include <cstdint>
#include <vector>

#include "core/model/model.h"
#include "core/stability/critical_step.h"

namespace organsim {

// Per point, without the tool term and before dividing by the mass, N/m:
// lambda_max(A_i) for all terms, and for the damped part alone (the
// springs, and the shear element when it has its damper). Zero at fixed
// points. `scale` is the d every row was computed with (npoint, positive at
// the free points).
struct GershgorinRows {
  std::vector<double> all;     // (npoint)
  std::vector<double> damped;  // (npoint)
  std::vector<double> scale;   // (npoint)
};

// The rows of `points` of `model` (through its gather layout) into rows.all
// and rows.damped, with the scale rows.scale.
void compute_gershgorin_rows(const Model& model, const std::vector<int32_t>& points, GershgorinRows& rows);

// Every row, with the scale from power iterations on B (the tool's k_c on
// the points `options` lets it touch is part of B's diagonal).
GershgorinRows gershgorin_rows(const Model& model, const CriticalStepOptions& options = {});

// Every row with a given scale (npoint, positive at the free points).
GershgorinRows gershgorin_rows_with_scale(const Model& model, std::vector<double> scale);

// The bound per point with the tool term of `options`, 1/s^2 (npoint).
std::vector<double> gershgorin_bounds(const Model& model, const GershgorinRows& rows,
                                      const CriticalStepOptions& options);

// Largest spring damping time d/k over the springs, s.
double spring_damping_time(const Model& model);

// Largest damping time c of the dampers D = c K: spring_damping_time and
// the shear element's tau, s.
double damping_time(const Model& model);

// A step every mode is stable at (position Verlet with the backends'
// dampers): lambda = the largest bound, damping rate c lambda_damped + alpha.
// Never above estimate_critical_step's dt_crit, which is this same value's
// dt_crit_gershgorin.
double guaranteed_critical_step(const Model& model, const GershgorinRows& rows, const CriticalStepOptions& options);

}  // namespace organsim
