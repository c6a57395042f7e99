#pragma once
// Block Gershgorin bounds on the eigenvalues of M^-1 K at rest, point by
// point, so that a topology change can recompute only the rows it touched.
//
// K has a 3x3 block per point pair. M^-1 K has the eigenvalues of the
// symmetric W = M^-1/2 K M^-1/2, whose block (i, j) is K_ij / sqrt(m_i m_j);
// for the free points every eigenvalue lambda satisfies, for some point i
// (block Gershgorin, Feingold-Varga, with spectral norms),
//   lambda <= (lambda_max(K_ii) + sum_{j free, j != i} ||K_ij|| sqrt(m_i / m_j)) / m_i.
// K_ii = sum of k_s u u^T over i's springs + sum of k_t g_i g_i^T over its
// tets (volume term per tet; the nodal term's blocks come from the nodal
// volumes of i's tets' points, see gershgorin.cpp) + the shear element's
// k_t (|g_i|^2 I + g_i g_i^T) + k_tool I, and
// ||K_ij|| <= sum of k_s + sum of k_t |g_i| |g_j| (the shear element's
// k_t (|g_i . g_j| + |g_i| |g_j|)) over what joins i and j. On the
// 2500-point liver this is 1.5 lambda_max, where scalar row sums of M^-1 K
// (|K_ii| <= its terms' sum, no mass weights) gave 2.9.
#include <cstdint>
#include <vector>

#include "core/model/model.h"
#include "core/stability/critical_step.h"

namespace organsim {

// Per point, without the tool term and before dividing by the mass, N/m:
// lambda_max(K_ii) + sum_j ||K_ij|| for all terms, and for the damped part
// alone (the springs, and the shear element when it has its damper). Zero
// at fixed points.
struct GershgorinRows {
  std::vector<double> all;     // (npoint)
  std::vector<double> damped;  // (npoint)
};

// Row `i` of `model` (through its gather layout) into rows.all[i] and rows.damped[i].
void compute_gershgorin_row(const Model& model, int32_t i, GershgorinRows& rows);

// Every row.
GershgorinRows gershgorin_rows(const Model& model);

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
