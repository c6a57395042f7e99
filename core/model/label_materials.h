#pragma once
// Stiffness of a Model whose tets have per-label materials
// (Model::tet_material): each tet contributes with its own material, by the
// rules of core/model/stiffness.h. Internal to core/model (model assembly).
#include <vector>

#include "core/model/model.h"

namespace organsim {

struct PerTetSprings {
  std::vector<double> k;  // N/m, per tissue spring (tet edge), in spring_ends order
  std::vector<double> d;  // N s/m
};

// k_e = sum over the tets t containing edge e of E_s(t) V_t / r_e^2, and the
// damper d_e = sum of tau(t) E_s(t) V_t / r_e^2: an interface edge takes each
// side's share from its own tets. model.spring_ends must be the tet edges.
PerTetSprings per_tet_material_springs(const Model& model);

// Sets tet_k (per-tet volume term: K(t) / V_t), point_volume_k (nodal term:
// the volume-weighted K of a point's tets over its nodal volume, K_a / V_a)
// and tet_shear_k (mu_e(t) V_t), each only when the materials have that term.
// model.point_rest_volume must be set.
void per_tet_material_volume_and_shear(Model& model);

}  // namespace organsim
