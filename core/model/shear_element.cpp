#include "core/model/shear_element.h"

#include <algorithm>

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

double shear_element_energy(const Model& model, const std::vector<Vec3>& x) {
  double e = 0;
  for (int32_t t = 0; t < static_cast<int32_t>(model.tet_shear_k.size()); ++t) {
    const Eigen::Matrix3d F = deformation_gradient(model, t, x);
    const Eigen::Matrix3d E = 0.5 * (F.transpose() * F - Eigen::Matrix3d::Identity());
    e += model.tet_shear_k[t] * E.squaredNorm();
  }
  return e;
}

void add_shear_element_forces(const Model& model, const std::vector<Vec3>& x, std::vector<Vec3>& force) {
  for (int32_t t = 0; t < static_cast<int32_t>(model.tet_shear_k.size()); ++t) {
    const Eigen::Matrix3d F = deformation_gradient(model, t, x);
    const Eigen::Matrix3d E = 0.5 * (F.transpose() * F - Eigen::Matrix3d::Identity());
    const Eigen::Matrix3d P = 2 * model.tet_shear_k[t] * F * E;  // V times the first Piola-Kirchhoff stress
    for (int i = 0; i < 4; ++i) force[model.tet_points[t][i]] -= P * model.tet_shape_gradient[t][i];
  }
}

Eigen::Matrix3d shear_element_rest_block(const Model& model, int32_t t, int i, int j) {
  const Vec3& gi = model.tet_shape_gradient[t][i];
  const Vec3& gj = model.tet_shape_gradient[t][j];
  return model.tet_shear_k[t] * (gi.dot(gj) * Eigen::Matrix3d::Identity() + gj * gi.transpose());
}

}  // namespace organsim
