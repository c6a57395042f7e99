// Per-label materials in the model assembly (see label_materials.h).
#include "core/model/label_materials.h"

#include "core/model/stiffness.h"
#include "core/model/tet_edges.h"

namespace organsim {

PerTetSprings per_tet_material_springs(const Model& model) {
  const int32_t ntet = model.ntet();
  std::vector<double> stiffness_volume(static_cast<size_t>(ntet)), damper_volume(static_cast<size_t>(ntet));
  for (int32_t t = 0; t < ntet; ++t) {
    const Material& m = model.material_of_tet(t);
    stiffness_volume[t] = spring_modulus(m) * model.tet_rest_volume[t];
    damper_volume[t] = m.spring_damping_time * stiffness_volume[t];
  }
  // tet_edges sums its per-tet values over each edge's tets, in tet order.
  const TetEdges k_sum = tet_edges(model.tet_points, model.npoint(), stiffness_volume);
  const TetEdges d_sum = tet_edges(model.tet_points, model.npoint(), damper_volume);
  PerTetSprings springs;
  springs.k.resize(k_sum.ends.size());
  springs.d.resize(k_sum.ends.size());
  for (size_t s = 0; s < k_sum.ends.size(); ++s) {
    const auto [a, b] = k_sum.ends[s];
    const double r2 = (model.rest_position[b] - model.rest_position[a]).squaredNorm();
    springs.k[s] = k_sum.volume[s] / r2;
    springs.d[s] = d_sum.volume[s] / r2;
  }
  return springs;
}

void per_tet_material_volume_and_shear(Model& model) {
  const int32_t ntet = model.ntet();
  model.tet_k.clear();
  model.point_volume_k.clear();
  model.tet_shear_k.clear();
  // The volume term's form: the first material with a volume term decides
  // (build_model checked that the others agree).
  const Material* with_volume = nullptr;
  bool shear = false;
  for (int32_t t = 0; t < ntet; ++t) {
    const Material& m = model.material_of_tet(t);
    if (!with_volume && volume_term_modulus(m) > 0) with_volume = &m;
    shear = shear || shear_element_modulus(m) > 0;
  }
  if (with_volume && volume_formulation(*with_volume) == VolumeFormulation::PerTet) {
    model.tet_k.resize(static_cast<size_t>(ntet));
    for (int32_t t = 0; t < ntet; ++t) {
      model.tet_k[t] = volume_term_modulus(model.material_of_tet(t)) / model.tet_rest_volume[t];
    }
  } else if (with_volume) {
    // K_a V_a = sum over the point's tets of K(t) V_t / 4, and k_a = K_a / V_a.
    std::vector<double> k_volume(static_cast<size_t>(model.npoint()), 0.0);
    for (int32_t t = 0; t < ntet; ++t) {
      const double share = volume_term_modulus(model.material_of_tet(t)) * model.tet_rest_volume[t] / 4;
      for (int32_t p : model.tet_points[t]) k_volume[p] += share;
    }
    model.point_volume_k.resize(k_volume.size());
    for (size_t a = 0; a < k_volume.size(); ++a) {
      const double v = model.point_rest_volume[a];
      model.point_volume_k[a] = v > 0 ? k_volume[a] / (v * v) : 0.0;
    }
  }
  if (shear) {
    model.tet_shear_k.resize(static_cast<size_t>(ntet));
    for (int32_t t = 0; t < ntet; ++t) {
      model.tet_shear_k[t] = shear_element_modulus(model.material_of_tet(t)) * model.tet_rest_volume[t];
    }
  }
}

}  // namespace organsim
