#include "core/model/shear_element.h"

#include <algorithm>
#include <cmath>

namespace organsim {

std::array<Vec3, 4> shape_gradients(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
  const Vec3 a = x1 - x0, b = x2 - x0, c = x3 - x0;
  const double six_v = a.dot(b.cross(c));
  std::array<Vec3, 4> g;
  g[1] = b.cross(c) / six_v;
  g[2] = c.cross(a) / six_v;
  g[3] = a.cross(b) / six_v;
  g[0] = -(g[1] + g[2] + g[3]);
  return g;
}

const Vec3& shape_gradient_of(const Model& model, int32_t t, int32_t point) {
  const Tet& tet = model.tet_points[t];
  return model.tet_shape_gradient[t][std::find(tet.begin(), tet.end(), point) - tet.begin()];
}

Eigen::Matrix3d deformation_gradient(const Model& model, int32_t t, const std::vector<Vec3>& x) {
  const Tet& tet = model.tet_points[t];
  const auto& g = model.tet_shape_gradient[t];
  // Relative to vertex 0 (sum g_i = 0), which keeps a far-from-origin mesh's
  // rounding out of F.
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  for (int i = 1; i < 4; ++i) F += (x[tet[i]] - x[tet[0]]) * g[i].transpose();
  return F;
}

namespace {

// Fbar_a of every point (npoint): I + sum over the tets of a of k_t (F_t - I) / K_a.
std::vector<Eigen::Matrix3d> smoothed_gradients(const Model& model, const std::vector<Vec3>& x) {
  std::vector<Eigen::Matrix3d> h(model.npoint(), Eigen::Matrix3d::Zero());
  for (int32_t t = 0; t < model.ntet(); ++t) {
    const Eigen::Matrix3d H = deformation_gradient(model, t, x) - Eigen::Matrix3d::Identity();
    for (int32_t a : model.tet_points[t]) h[a] += model.tet_shear_k[t] * H;
  }
  for (int32_t a = 0; a < model.npoint(); ++a)
    h[a] = Eigen::Matrix3d::Identity() + (model.point_shear_k[a] > 0 ? h[a] / model.point_shear_k[a] : h[a]);
  return h;
}

}  // namespace

double shear_element_energy(const Model& model, const std::vector<Vec3>& x) {
  const double s = model.shear_smoothed_share;
  double e = 0;
  for (int32_t t = 0; t < static_cast<int32_t>(model.tet_shear_k.size()); ++t)
    e += (1 - s) * model.tet_shear_k[t] * force_law::shear_energy_density(deformation_gradient(model, t, x));
  if (model.has_smoothed_shear()) {
    const std::vector<Eigen::Matrix3d> F = smoothed_gradients(model, x);
    for (int32_t a = 0; a < model.npoint(); ++a)
      if (model.point_shear_k[a] > 0) e += smoothed_shear_patch_k(model, a) * force_law::shear_energy_density(F[a]);
  }
  return e;
}

std::vector<Eigen::Matrix3d> smoothed_shear_stress(const Model& model, const std::vector<Vec3>& x) {
  std::vector<Eigen::Matrix3d> P(model.npoint(), Eigen::Matrix3d::Zero());
  if (!model.has_smoothed_shear()) return P;
  const std::vector<Eigen::Matrix3d> F = smoothed_gradients(model, x);
  for (int32_t a = 0; a < model.npoint(); ++a)
    if (model.point_shear_k[a] > 0) P[a] = force_law::shear_stress(F[a]);
  return P;
}

void add_shear_element_forces(const Model& model, const std::vector<Vec3>& x, std::vector<Vec3>& force) {
  if (!model.has_shear_element()) return;
  const double s = model.shear_smoothed_share;
  const std::vector<Eigen::Matrix3d> Pa = smoothed_shear_stress(model, x);
  for (int32_t t = 0; t < model.ntet(); ++t) {
    const Tet& tet = model.tet_points[t];
    const Eigen::Matrix3d Pbar = (Pa[tet[0]] + Pa[tet[1]] + Pa[tet[2]] + Pa[tet[3]]) / 4;
    // V times the first Piola-Kirchhoff stress of the blend.
    const Eigen::Matrix3d P = model.tet_shear_k[t] * ((1 - s) * force_law::shear_stress(deformation_gradient(model, t, x)) + s * Pbar);
    for (int i = 0; i < 4; ++i) force[tet[i]] -= P * model.tet_shape_gradient[t][i];
  }
}

void add_shear_element_damping_forces(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                                      std::vector<Vec3>& force) {
  if (!(model.shear_damping_time > 0)) return;
  for (int32_t t = 0; t < static_cast<int32_t>(model.tet_shear_k.size()); ++t) {
    const Eigen::Matrix3d F = deformation_gradient(model, t, x);
    const Eigen::Matrix3d Fdot = deformation_gradient(model, t, v);  // sum_i v_i g_i^T
    const Eigen::Matrix3d cof = force_law::shear_cofactor(F);
    // V times the viscous first Piola-Kirchhoff stress J sigma F^-T = 2 mu_e tau D cof.
    const Eigen::Matrix3d P = model.tet_shear_k[t] * force_law::shear_damping_stress(
                                                         Fdot, cof, F.col(0).dot(cof.col(0)), model.shear_damping_time);
    for (int i = 0; i < 4; ++i) force[model.tet_points[t][i]] -= P * model.tet_shape_gradient[t][i];
  }
}

Eigen::Matrix3d shear_element_rest_block(const Model& model, int32_t t, int i, int j) {
  const Vec3& gi = model.tet_shape_gradient[t][i];
  const Vec3& gj = model.tet_shape_gradient[t][j];
  return model.tet_shear_k[t] * force_law::shear_rest_stiffness(gi, gj);
}

std::vector<ShearPatchEntry> smoothed_shear_patch(const Model& model, int32_t a) {
  std::vector<ShearPatchEntry> patch;
  if (!model.has_smoothed_shear() || !(model.point_shear_k[a] > 0)) return patch;
  const int32_t c = model.layout.chunk_size;
  const int32_t first = model.layout.tets.chunk_offset[a / c] + a % c;
  for (int32_t j = 0; j < model.layout.tets.count[a]; ++j) {
    const int32_t t = model.layout.tets.item[first + j * c];
    for (int i = 0; i < 4; ++i) {
      const int32_t p = model.tet_points[t][i];
      const Vec3 w = model.tet_shear_k[t] / model.point_shear_k[a] * model.tet_shape_gradient[t][i];
      auto it = std::find_if(patch.begin(), patch.end(), [&](const ShearPatchEntry& e) { return e.point == p; });
      if (it == patch.end())
        patch.push_back({p, w});
      else
        it->w += w;
    }
  }
  return patch;
}

}  // namespace organsim
