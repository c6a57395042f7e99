#pragma once
// How a Material becomes spring and volume stiffness: the one rule that
// build_model (and any rebuild after a topology change) uses. docs/physics.md
// derives it; docs/validation.md measures it against elasticity theory.
//
// A tet spring lattice is a central-force ("Cauchy") solid: on its own it has
// Lame constants lambda = mu, i.e. Poisson ratio 1/4. With
//   k_e = E_s * (sum of the rest volumes of the tets sharing e) / r_e^2
// and edge directions spread evenly, the springs store the energy of a linear
// solid of modulus E_s with nu = 1/4 (mu_s = lambda_s = 0.4 E_s). The volume
// term K_v/2 (V - V_r)^2 / V_r adds K_v to lambda only; the shear element
// (core/model/shear_element.h) adds mu_e to mu only. So a material (E, nu),
// lambda = E nu / ((1 + nu) (1 - 2 nu)), mu = E / (2 (1 + nu)), gets
//   nu >= 1/4: springs mu_s = mu (E_s = 2.5 mu), K_v = lambda - mu >= 0, no element;
//   nu <  1/4: springs mu_s = lambda (E_s = 2.5 lambda), mu_e = mu - lambda > 0, no volume term.
// Both branches meet at nu = 1/4 (lambda = mu: springs only), and every
// part is non-negative, so the stiffness stays positive definite for any
// 0 <= nu < 1/2 (a negative volume term did not: docs/validation.md).
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "core/mesh/tet_mesh.h"
#include "core/model/material.h"

namespace organsim {

// The Poisson ratios a material may ask for: [kMinPoissonRatio, 0.5).
inline constexpr double kMinPoissonRatio = 0.0;
// Below this ratio the springs carry lambda and the shear element the rest of mu.
inline constexpr double kShearElementBelowPoissonRatio = 0.25;

// E_s of the spring formula above, Pa: young_modulus without a Poisson ratio
// (the old rule), with one 2.5 mu for nu >= 1/4 and 2.5 lambda below (0 at
// nu = 0: the shear element then carries all of the stiffness).
double spring_modulus(const Material& material);

// K_v of the volume term, Pa: volume_modulus without a Poisson ratio,
// lambda - mu with one for nu >= 1/4, 0 below.
double volume_term_modulus(const Material& material);

// mu_e of the shear element, Pa: mu - lambda for a Poisson ratio below 1/4,
// else 0 (no element).
double shear_element_modulus(const Material& material);

// The share s of the shear element's stiffness carried on node-smoothed
// deformation gradients (core/model/shear_element.h): kShearSmoothedShare
// with the smoothed formulation, 0 per tet or without the element.
inline constexpr double kShearSmoothedShare = 0.5;
double shear_smoothed_share(const Material& material);
const char* shear_formulation_name(ShearFormulation formulation);  // "per_tet" or "smoothed"

// Lame constants of the linear solid the model approximates, Pa: with a
// Poisson ratio the asked (E, nu); without one mu = 0.4 E_s and
// lambda = 0.4 E_s + volume_modulus (what the old rule actually gives).
struct EffectiveElasticity {
  double young_modulus = 0;  // Pa
  double poisson_ratio = 0;
  double shear_modulus = 0;  // mu, Pa
  double lame_lambda = 0;    // Pa
};
EffectiveElasticity effective_elasticity(const Material& material);

// For a run's meta: the rule used ("poisson_ratio" or "springs + volume_modulus"
// or "spring_stiffness") and the effective E (Pa) and nu, so a study can
// compare its forces with theory. docs/validation.md says how close the mesh
// gets to them.
nlohmann::json elasticity_json(const Material& material);

// Stiffness of each spring, N/m: the constant spring_stiffness when given,
// else E_s * V_e / r_e^2 with V_e (`edge_volume`, nspring) the summed rest
// volume of the tets that contain spring e (core/model/tet_edges.h);
// `points` are the rest positions.
std::vector<double> spring_stiffness(const Material& material, const std::vector<Vec3>& points,
                                     const std::vector<Edge>& spring_ends, const std::vector<double>& edge_volume);

// Tool contact and grasp: the scenario's contact_stiffness k_c is what a
// point of the median free mass m_med feels; a lighter point gets
// k_c m_i / m_med, so the tool adds at most k_c / m_med to any point's
// omega^2 and a light corner or sliver point cannot set the time step.
// Returns min(1, m_i / m_med) per point (npoint); 1 where nothing is free.
std::vector<double> tool_stiffness_scale(const std::vector<double>& mass, const std::vector<uint8_t>& fixed);

// The volume term's form: material.volume_formulation when given, else
// nodal with a Poisson ratio and per tet without one.
VolumeFormulation volume_formulation(const Material& material);
const char* volume_formulation_name(VolumeFormulation formulation);  // "per_tet" or "nodal"

// Per-tet volume stiffness K_v / V_r, N/m^5; empty when the volume term is off
// (K_v == 0) or nodal.
std::vector<double> tet_volume_stiffness(const Material& material, const std::vector<double>& tet_rest_volume);

// Per-tet shear element stiffness k_t = mu_e V_t^r, J (ntet); empty when
// the element is off (mu_e == 0).
std::vector<double> tet_shear_stiffness(const Material& material, const std::vector<double>& tet_rest_volume);

// Nodal rest volumes V_a^r = sum of V_t^r / 4 over the tets of a, m^3 (npoint;
// 0 for a point in no tet).
std::vector<double> nodal_rest_volume(int32_t npoint, const std::vector<Tet>& tets,
                                      const std::vector<double>& tet_rest_volume);

// Per-point nodal volume stiffness K_v / V_a^r, N/m^5 (0 for a point in no
// tet); empty when the volume term is off or per tet.
std::vector<double> nodal_volume_stiffness(const Material& material, const std::vector<double>& nodal_rest_volume);

}  // namespace organsim
