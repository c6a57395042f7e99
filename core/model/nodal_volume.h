#pragma once
// The averaged nodal volume term in double precision, for the code that
// evaluates it outside the kernels (reference forces, energy, the CPU-side
// oracles). Energy sum_a k_a/2 (V_a - V_a^r)^2 with V_a = sum of V_t / 4 over
// the tets of a; the force on x_i is -sum_t p_t dV_t/dx_i with the tet
// pressure p_t = (1/4) sum over the tet's vertices of q_a = k_a (V_a - V_a^r).
// docs/physics.md derives it.
#include <vector>

#include "core/model/model.h"

namespace organsim {

// Nodal volumes V_a at positions x (internal numbering), m^3 (npoint). Summed
// in tet order, like nodal_rest_volume(), so the rest state gives V_a^r exactly.
void nodal_volumes(const Model& model, const std::vector<Vec3>& x, std::vector<double>& out);

// Nodal pressures q_a = k_a (V_a - V_a^r), Pa (npoint); all zero without the nodal term.
void nodal_pressures(const Model& model, const std::vector<Vec3>& x, std::vector<double>& out);

}  // namespace organsim
