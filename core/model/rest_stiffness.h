#pragma once
// The force law linearised at rest, assembled as sparse triplets over the
// 3 npoint coordinates (point p's axis a is coordinate 3 p + a): what the
// static solve factors, the Gershgorin bound's diagonal reads and the
// implicit integrator's rest-system preconditioner factors
// (core/sim/implicit_system.h).
#include <Eigen/SparseCore>
#include <vector>

#include "core/model/model.h"

namespace organsim {

using Triplets = std::vector<Eigen::Triplet<double>>;

// K = -df/dx at rest: springs k u u^T between their ends, the volume term
// k_v g_i g_j^T per tet or G^T diag(k_a) G nodal, the shear element
// k_t ((g_i . g_j) I + g_j g_i^T) per tet ((1 - s) of it with a smoothed
// share s) and its node patches (force_law.h, "Rest stiffness").
// `terms` ShearElement: only the shear element's part (the implicit
// integrator keeps it as a constant matrix: core/sim/implicit_system.h).
enum class RestTerms { All, ShearElement };
Triplets rest_stiffness(const Model& model, RestTerms terms = RestTerms::All);

// D = -df/dv at rest: the springs' dampers d u u^T, the shear element's
// damper tau times its per-tet blocks (core/model/shear_element.h), and the
// drag alpha m I on every point (ShearElement: the element's damper only).
Triplets rest_damping(const Model& model, RestTerms terms = RestTerms::All);

// M: each point's lumped mass on its three coordinates.
Triplets lumped_mass(const Model& model);

// M + h D_rest + beta K_rest (beta = h^2 with the stiffness in the system,
// 0 without): the rest system the implicit integrator's preconditioners
// factor or project (core/sim/reference_backend.cpp, core/sim/coarse_space.h).
Triplets rest_system(const Model& model, double h, double beta);

// The sparse matrix of `triplets` (duplicates summed), 3 npoint square.
Eigen::SparseMatrix<double> assemble(const Model& model, const Triplets& triplets);

}  // namespace organsim
