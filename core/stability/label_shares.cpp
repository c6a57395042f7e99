#include "core/stability/label_shares.h"

#include <algorithm>
#include <map>

namespace organsim {

std::vector<LabelModeShare> mode_share_by_label(const Model& model, const std::vector<double>& point_share) {
  if (model.tet_label.empty()) return {};
  // The mass each point has from its tets (the lumped mass without what the
  // assembly may add elsewhere), so the split of a share sums to the share.
  std::vector<double> tet_mass_of_point(model.npoint(), 0.0);
  const auto quarter_mass = [&](int32_t t) { return model.material_of_tet(t).density * model.tet_rest_volume[t] / 4; };
  for (int32_t t = 0; t < model.ntet(); ++t)
    for (int32_t p : model.tet_points[t]) tet_mass_of_point[p] += quarter_mass(t);
  std::map<int32_t, double> by_label;
  for (int32_t t = 0; t < model.ntet(); ++t) {
    double& share = by_label[model.tet_label[t]];
    for (int32_t p : model.tet_points[t]) {
      if (tet_mass_of_point[p] > 0) share += point_share[p] * quarter_mass(t) / tet_mass_of_point[p];
    }
  }
  double total = 0;
  for (const auto& [label, share] : by_label) total += share;
  std::vector<LabelModeShare> out;
  for (const auto& [label, share] : by_label) out.push_back({label, total > 0 ? share / total : 0});
  std::stable_sort(out.begin(), out.end(), [](const LabelModeShare& a, const LabelModeShare& b) { return a.share > b.share; });
  return out;
}

}  // namespace organsim
