#include "core/topology/run_events.h"

#include <algorithm>
#include <chrono>

#include "core/topology/blade.h"

namespace organsim {

TopologyEvents::TopologyEvents(const EventsDef& events, const Model& initial)
    : events_(events), editor_(initial), step_check_(initial) {
  if (events.tear) {
    TearSettings s;
    s.strain = events.tear->strain;
    s.ticks = events.tear->ticks;
    s.max_per_tick = events.tear->max_per_tick;
    tear_.emplace(s);
  }
}

bool TopologyEvents::active(double t0, double t1) const {
  for (const CutEvent& c : events_.cuts)
    if (t1 > c.start() && t0 < c.end()) return true;
  return events_.tear && t1 > events_.tear->start;
}

bool TopologyEvents::before_tick(double t0, double t1, const Model& current, const std::vector<Vec3>& x,
                                 Model& next) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<int32_t> faces;
  nlohmann::json sources = nlohmann::json::array();
  for (const CutEvent& c : events_.cuts) {
    if (!(t1 > c.start() && t0 < c.end())) continue;
    BladeSweep sweep;
    c.blade_at(t0, sweep.a0, sweep.b0);
    c.blade_at(t1, sweep.a1, sweep.b1);
    const auto cut = faces_cut_by_blade(sweep, editor_.faces(), current.tet_points, x, editor_.separated());
    if (cut.empty()) continue;
    faces.insert(faces.end(), cut.begin(), cut.end());
    sources.push_back({{"kind", "cut"}, {"name", c.name}, {"faces", cut.size()}});
  }
  if (tear_ && t1 > events_.tear->start) {
    const auto torn = tear_->update(current, x, editor_.faces(), editor_.separated());
    if (!torn.empty()) {
      faces.insert(faces.end(), torn.begin(), torn.end());
      sources.push_back({{"kind", "tear"}, {"faces", torn.size()}});
    }
  }
  if (faces.empty()) return false;
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  ChangeCounts counts;
  const bool changed = editor_.separate(current, faces, next, counts);
  if (!changed) {
    unopened_faces_ += counts.faces_separated;
    return false;
  }
  std::string kind;
  for (const auto& source : sources) {
    const std::string k = source["kind"];
    if (kind.find(k) == std::string::npos) kind += (kind.empty() ? "" : "+") + k;
  }
  pending_ = {
      {"t", t0},
      {"kind", kind},
      {"sources", sources},
      {"faces_separated", counts.faces_separated + unopened_faces_},
      {"points_split", counts.points_split},
      {"points_added", counts.points_added},
      {"springs_added", counts.springs_added},
      {"springs_removed", counts.springs_removed},
      {"points", next.npoint()},
      {"springs", next.nspring()},
      {"model_ms", 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()},
  };
  unopened_faces_ = 0;
  return true;
}

double TopologyEvents::guaranteed_step(const Model& previous, const Model& next, const CriticalStepOptions& options) {
  step_check_.update(previous, next);
  return step_check_.guaranteed_step(next, options);
}

void TopologyEvents::changed(const Model& previous, const Model& next, double rebuild_seconds,
                             double dt_crit_guaranteed, const StabilityReport* full, double check_seconds) {
  if (tear_) tear_->model_changed(previous, next);
  pending_["backend_rebuild_ms"] = 1e3 * rebuild_seconds;
  pending_["dt_crit_guaranteed"] = dt_crit_guaranteed;
  pending_["dt_check"] = full ? "power iteration" : "gershgorin";
  if (full) pending_["dt_crit"] = full->dt_crit;
  pending_["dt_check_ms"] = 1e3 * check_seconds;
  log_.push_back(std::move(pending_));
  pending_ = nlohmann::json();
}

}  // namespace organsim
