#include "core/model/stiffness.h"

#include <algorithm>
#include <nlohmann/json.hpp>

namespace organsim {

namespace {

// Lame constants of the asked (E, nu).
double lame_mu(const Material& m) { return m.young_modulus / (2.0 * (1.0 + *m.poisson_ratio)); }
double lame_lambda(const Material& m) {
  const double nu = *m.poisson_ratio;
  return m.young_modulus * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
}
bool below_lattice_ratio(const Material& m) {
  return m.poisson_ratio && *m.poisson_ratio < kShearElementBelowPoissonRatio;
}

}  // namespace

double spring_modulus(const Material& m) {
  if (!m.poisson_ratio) return m.young_modulus;
  return 2.5 * (below_lattice_ratio(m) ? lame_lambda(m) : lame_mu(m));
}

double volume_term_modulus(const Material& m) {
  if (!m.poisson_ratio) return m.volume_modulus;
  if (below_lattice_ratio(m)) return 0.0;
  const double nu = *m.poisson_ratio;
  return m.young_modulus * (4.0 * nu - 1.0) / (2.0 * (1.0 + nu) * (1.0 - 2.0 * nu));
}

double shear_element_modulus(const Material& m) {
  if (!below_lattice_ratio(m)) return 0.0;
  return lame_mu(m) - lame_lambda(m);
}

double shear_smoothed_share(const Material& m) {
  return shear_element_modulus(m) > 0 && m.shear_formulation == ShearFormulation::Smoothed ? kShearSmoothedShare : 0.0;
}

const char* shear_formulation_name(ShearFormulation f) {
  return f == ShearFormulation::Smoothed ? "smoothed" : "per_tet";
}

EffectiveElasticity effective_elasticity(const Material& m) {
  EffectiveElasticity e;
  e.shear_modulus = 0.4 * spring_modulus(m) + shear_element_modulus(m);
  e.lame_lambda = 0.4 * spring_modulus(m) + volume_term_modulus(m);
  const double mu = e.shear_modulus, lambda = e.lame_lambda;
  e.young_modulus = mu * (3 * lambda + 2 * mu) / (lambda + mu);
  e.poisson_ratio = lambda / (2 * (lambda + mu));
  return e;
}

nlohmann::json elasticity_json(const Material& m) {
  if (m.spring_stiffness) return {{"rule", "spring_stiffness"}, {"spring_stiffness", *m.spring_stiffness}};
  const EffectiveElasticity e = effective_elasticity(m);
  return {{"rule", m.poisson_ratio ? "poisson_ratio" : "springs + volume_modulus"},
          // Below nu = 1/4 there is no volume term to name.
          {"volume_formulation", shear_element_modulus(m) > 0 ? "none" : volume_formulation_name(volume_formulation(m))},
          {"young_modulus", e.young_modulus},
          {"poisson_ratio", e.poisson_ratio},
          {"spring_modulus", spring_modulus(m)},
          {"volume_term_modulus", volume_term_modulus(m)},
          {"shear_element_modulus", shear_element_modulus(m)},
          {"shear_formulation", shear_element_modulus(m) > 0 ? shear_formulation_name(m.shear_formulation) : "none"}};
}

std::vector<double> spring_stiffness(const Material& material, const std::vector<Vec3>& points,
                                     const std::vector<Edge>& spring_ends, const std::vector<double>& edge_volume) {
  const size_t nspring = spring_ends.size();
  if (material.spring_stiffness) return std::vector<double>(nspring, *material.spring_stiffness);
  const double modulus = spring_modulus(material);
  std::vector<double> k(nspring);
  for (size_t s = 0; s < nspring; ++s) {
    const double r2 = (points[spring_ends[s][1]] - points[spring_ends[s][0]]).squaredNorm();
    k[s] = modulus * edge_volume[s] / r2;
  }
  return k;
}

std::vector<double> tool_stiffness_scale(const std::vector<double>& mass, const std::vector<uint8_t>& fixed) {
  std::vector<double> free_mass;
  for (size_t i = 0; i < mass.size(); ++i)
    if (!fixed[i] && mass[i] > 0) free_mass.push_back(mass[i]);
  std::vector<double> scale(mass.size(), 1.0);
  if (free_mass.empty()) return scale;
  const auto middle = free_mass.begin() + static_cast<std::ptrdiff_t>(free_mass.size() / 2);
  std::nth_element(free_mass.begin(), middle, free_mass.end());
  const double median = *middle;
  for (size_t i = 0; i < mass.size(); ++i) scale[i] = std::min(1.0, mass[i] / median);
  return scale;
}

VolumeFormulation volume_formulation(const Material& m) {
  if (m.volume_formulation) return *m.volume_formulation;
  return m.poisson_ratio ? VolumeFormulation::Nodal : VolumeFormulation::PerTet;
}

const char* volume_formulation_name(VolumeFormulation f) {
  return f == VolumeFormulation::Nodal ? "nodal" : "per_tet";
}

std::vector<double> tet_volume_stiffness(const Material& material, const std::vector<double>& tet_rest_volume) {
  const double modulus = volume_term_modulus(material);
  std::vector<double> k;
  if (modulus == 0 || volume_formulation(material) != VolumeFormulation::PerTet) return k;
  k.resize(tet_rest_volume.size());
  for (size_t t = 0; t < k.size(); ++t) k[t] = modulus / tet_rest_volume[t];
  return k;
}

std::vector<double> tet_shear_stiffness(const Material& material, const std::vector<double>& tet_rest_volume) {
  const double modulus = shear_element_modulus(material);
  std::vector<double> k;
  if (modulus == 0) return k;
  k.resize(tet_rest_volume.size());
  for (size_t t = 0; t < k.size(); ++t) k[t] = modulus * tet_rest_volume[t];
  return k;
}

std::vector<double> nodal_rest_volume(int32_t npoint, const std::vector<Tet>& tets,
                                      const std::vector<double>& tet_rest_volume) {
  std::vector<double> v(static_cast<size_t>(npoint), 0.0);
  for (size_t t = 0; t < tets.size(); ++t)
    for (int32_t p : tets[t]) v[p] += tet_rest_volume[t] / 4;
  return v;
}

std::vector<double> nodal_volume_stiffness(const Material& material, const std::vector<double>& nodal_rest_volume) {
  const double modulus = volume_term_modulus(material);
  std::vector<double> k;
  if (modulus == 0 || volume_formulation(material) != VolumeFormulation::Nodal) return k;
  k.resize(nodal_rest_volume.size());
  for (size_t a = 0; a < k.size(); ++a) k[a] = nodal_rest_volume[a] > 0 ? modulus / nodal_rest_volume[a] : 0.0;
  return k;
}

}  // namespace organsim
