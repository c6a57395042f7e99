#include "core/topology/change_cost.h"

#include <algorithm>
#include <chrono>
#include <vector>

#include "core/sim/cpu_backend.h"
#include "core/stability/critical_step.h"
#include "core/stability/step_after_change.h"
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

// See change_cost.h: a blade of 4 h sweeping 3 h through the tet centroid
// nearest the bounding box's centre.
BladeSweep local_blade(const Model& model) {
  Vec3 lo = model.rest_position.front(), hi = lo;
  for (const Vec3& p : model.rest_position) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 middle = 0.5 * (lo + hi);
  Vec3 centre = middle;
  double best = -1;
  for (const Tet& t : model.tet_points) {
    const auto& x = model.rest_position;
    const Vec3 c = 0.25 * (x[t[0]] + x[t[1]] + x[t[2]] + x[t[3]]);
    if (best < 0 || (c - middle).squaredNorm() < best) best = (c - middle).squaredNorm(), centre = c;
  }
  std::vector<double> rest = model.spring_rest;
  std::nth_element(rest.begin(), rest.begin() + rest.size() / 2, rest.end());
  const double h = rest[rest.size() / 2];
  BladeSweep sweep;
  sweep.a0 = centre + Vec3(0, -2 * h, 1.5 * h);
  sweep.b0 = centre + Vec3(0, 2 * h, 1.5 * h);
  sweep.a1 = centre + Vec3(0, -2 * h, -1.5 * h);
  sweep.b1 = centre + Vec3(0, 2 * h, -1.5 * h);
  return sweep;
}

}  // namespace

ChangeCost measure_change_cost(const Model& model, int repeats) {
  const BladeSweep sweep = local_blade(model);
  ChangeCost cost;
  std::vector<double> detect, rebuild, backend_ms, check, dt_crit;
  for (int i = 0; i < std::max(repeats, 1); ++i) {
    auto backend = make_cpu_backend(model, {}, {Precision::Double, 1});
    TopologyEditor editor(model);
    ChangeStepCheck step_check(model);
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
    step_check.update(model, next);
    const double guaranteed = step_check.guaranteed_step(next, {});
    check.push_back(ms_since(start));
    start = std::chrono::steady_clock::now();
    const StabilityReport full = estimate_critical_step(next);
    dt_crit.push_back(ms_since(start));
    cost.faces_separated = counts.faces_separated;
    cost.points_added = counts.points_added;
    cost.guaranteed_over_dt_crit = guaranteed / full.dt_crit;
  }
  cost.detect_ms = median(detect);
  cost.model_ms = median(rebuild);
  cost.backend_ms = median(backend_ms);
  cost.dt_check_ms = median(check);
  cost.dt_crit_ms = median(dt_crit);
  return cost;
}

}  // namespace organsim
