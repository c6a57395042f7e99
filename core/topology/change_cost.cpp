#include "core/topology/change_cost.h"

#include <algorithm>
#include <chrono>
#include <vector>

#include "core/sim/cpu_backend.h"
#include "core/stability/critical_step.h"
#include "core/topology/blade.h"
#include "core/topology/topology_editor.h"

namespace organsim {

namespace {

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

ChangeCost measure_change_cost(const Model& model, int repeats) {
  Vec3 lo = model.rest_position.front(), hi = lo;
  for (const Vec3& p : model.rest_position) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 c = 0.5 * (lo + hi), size = hi - lo;
  BladeSweep sweep;
  sweep.a0 = c + Vec3(0, -0.1 * size.y(), 0.1 * size.z());
  sweep.b0 = c + Vec3(0, 0.1 * size.y(), 0.1 * size.z());
  sweep.a1 = c + Vec3(0, -0.1 * size.y(), 0);
  sweep.b1 = c + Vec3(0, 0.1 * size.y(), 0);

  ChangeCost cost;
  std::vector<double> detect, rebuild, backend_ms, dt_crit;
  for (int i = 0; i < std::max(repeats, 1); ++i) {
    auto backend = make_cpu_backend(model, {}, {Precision::Double, 1});
    TopologyEditor editor(model);
    auto start = std::chrono::steady_clock::now();
    const auto faces = faces_cut_by_blade(sweep, editor.faces(), model.tet_points, model.rest_position,
                                          editor.separated());
    detect.push_back(ms_since(start));
    Model next;
    ChangeCounts counts;
    start = std::chrono::steady_clock::now();
    if (!editor.separate(model, faces, next, counts)) return cost;  // nothing to cut: zeros
    rebuild.push_back(ms_since(start));
    start = std::chrono::steady_clock::now();
    backend->rebuild(next);
    backend_ms.push_back(ms_since(start));
    start = std::chrono::steady_clock::now();
    estimate_critical_step(next);
    dt_crit.push_back(ms_since(start));
    cost.faces_separated = counts.faces_separated;
    cost.points_added = counts.points_added;
  }
  cost.detect_ms = median(detect);
  cost.model_ms = median(rebuild);
  cost.backend_ms = median(backend_ms);
  cost.dt_crit_ms = median(dt_crit);
  return cost;
}

}  // namespace organsim
