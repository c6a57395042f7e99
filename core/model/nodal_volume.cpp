#include "core/model/nodal_volume.h"

namespace organsim {

void nodal_volumes(const Model& model, const std::vector<Vec3>& x, std::vector<double>& out) {
  out.assign(model.npoint(), 0.0);
  for (const Tet& t : model.tet_points) {
    const double v = signed_volume(x[t[0]], x[t[1]], x[t[2]], x[t[3]]);
    for (int32_t p : t) out[p] += v / 4;
  }
}

void nodal_pressures(const Model& model, const std::vector<Vec3>& x, std::vector<double>& out) {
  if (!model.has_nodal_volume()) {
    out.assign(model.npoint(), 0.0);
    return;
  }
  nodal_volumes(model, x, out);
  for (int32_t a = 0; a < model.npoint(); ++a)
    out[a] = model.point_volume_k[a] * (out[a] - model.point_rest_volume[a]);
}

}  // namespace organsim
