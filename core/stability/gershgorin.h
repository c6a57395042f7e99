#pragma once
// Guaranteed upper bounds on the eigenvalues of M^-1 K at rest, point by
// point, so that a topology change can recompute only the rows it touched.
//
// M^-1 K has the eigenvalues of the symmetric W = M^-1/2 K M^-1/2 over the
// free points. K is a sum of positive semi-definite element matrices K_e
// (a spring, a tet's volume term, a node's nodal volume term, a tet's shear
// element, a node's smoothed shear patch), and each K_e is at most a
// block-diagonal majorant D_e (x^T K_e x <= x^T D_e x for every x):
// - rank-one forms k (sum_c v_c . x_c)^2 (springs, volume terms), by
//   Cauchy-Schwarz with any positive tau_c over the element's free points:
//   D_e,cc = (T_e / tau_c) K_e,cc, T_e = sum_c tau_c;
// - the shear forms (rank up to six), by |x_i||x_c| <= (r |x_i|^2 +
//   |x_c|^2 / r) / 2 with r = tau_c / tau_i, the Gershgorin form:
//   D_e,ii = K_e,ii + sum_{c != i} ||K_e,ic|| tau_c / tau_i I.
// Summed over the elements, K <= blockdiag(A_i), A_i = sum_e D_e,ii, so
// lambda_max(W) <= max_i lambda_max(A_i + k_c I) / m_i: the point's row (the
// tool adds k_c I). organsim takes tau_ec = |v_ec| d_c / sqrt(m_c) (|v_ec|:
// the length of c's part of the form) with one scale d per point. With
// d = 1 each row is at most the block Gershgorin row of W,
// (lambda_max(K_ii) + sum_j ||K_ij|| sqrt(m_i / m_j)) / m_i with ||K_ij||
// bounded by its elements' terms; keeping A_i a matrix lets the directions
// of a point's springs and faces share the bound instead of adding up. Any
// positive d is a proof, so d is fitted (gershgorin_rows). On the paper's
// 7656-point liver (poisson_ratio 0.45, the tool on 905 points) the bound is
// 1.08 lambda_max after fitting d (1.61 at d = 1; block Gershgorin rows with
// bounded ||K_ij||: 3.06; docs/stability.md). The file keeps the name of the
// block Gershgorin bound that these rows refine, as do the JSON keys.
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

// Every row, with a fitted scale: from d = 1, each d_i is multiplied by its
// row's bound (with the tool's k_c on the points `options` lets it touch)
// 20 times, and the d whose rows guarantee the largest step is kept.
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
