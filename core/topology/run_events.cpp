#include "core/topology/run_events.h"

#include <algorithm>
#include <chrono>

#include "core/model/model_rebuild.h"
#include "core/topology/blade.h"

namespace organsim {

double suture_tension_max(const Model& model, const std::vector<Vec3>& x, double t) {
  double tension = 0;
  for (int32_t s = model.first_suture(); s < model.nspring(); ++s) {
    const Suture& u = model.suture_of_spring(s);
    tension = std::max(tension, u.k * std::max(0.0, (x[u.ends[1]] - x[u.ends[0]]).norm() - u.rest_at(t)));
  }
  return tension;
}

nlohmann::json suture_summary(const Model& model, const std::vector<Vec3>& x, double t, double tension_peak) {
  double tied = 0, length = 0;
  for (int32_t s = model.first_suture(); s < model.nspring(); ++s) {
    const Suture& u = model.suture_of_spring(s);
    tied = std::max(tied, u.length);
    length = std::max(length, (x[u.ends[1]] - x[u.ends[0]]).norm());
  }
  return {{"count", model.nsuture()},
          {"tied_length_max_m", tied},
          {"length_max_m", length},
          {"tension_end_N", suture_tension_max(model, x, t)},
          {"tension_max_N", tension_peak}};
}

TopologyEvents::TopologyEvents(const EventsDef& events, const Model& initial)
    : events_(events), editor_(initial), cut_records_(events.cuts.size()), tied_(events.sutures.size(), 0),
      step_check_(initial) {
  for (size_t i = 0; i < events_.cuts.size(); ++i) cut_records_[i].cut = &events_.cuts[i];
  if (events.tear) {
    TearSettings s;
    s.strain = events.tear->strain;
    s.ticks = events.tear->ticks;
    s.max_per_tick = events.tear->max_per_tick;
    tear_.emplace(s);
  }
}

void TopologyEvents::add_cut(CutEvent cut) {
  events_.cuts.push_back(std::move(cut));
  cut_records_.emplace_back();
  // The vector may have moved: every record points into it again.
  for (size_t i = 0; i < events_.cuts.size(); ++i) cut_records_[i].cut = &events_.cuts[i];
}

bool TopologyEvents::suture_due(size_t i, double t0, double t1) const {
  // The first tick that starts at or after t (a millionth of a tick of slack for rounding in i * tick).
  return !tied_[i] && t0 + 1e-6 * (t1 - t0) >= events_.sutures[i].t;
}

bool TopologyEvents::active(double t0, double t1) const {
  for (const CutEvent& c : events_.cuts)
    if (t1 > c.start() && t0 < c.end()) return true;
  for (size_t i = 0; i < tied_.size(); ++i)
    if (suture_due(i, t0, t1)) return true;
  return events_.tear && t1 > events_.tear->start;
}

OffPathPlan TopologyEvents::off_path(double t0, double t1, double dt) const {
  OffPathPlan plan;
  bool when_ready = false;
  for (const CutEvent& c : events_.cuts) {
    if (!(t1 > c.start() && t0 < c.end())) continue;
    // applied_at at this tick (within half a step) is a cut made and applied at once.
    const bool later = c.when_ready || (c.applied_at && !(t0 >= *c.applied_at - 0.5 * dt));
    if (!later) return {};
    plan.off = true;
    when_ready = when_ready || c.when_ready;
    if (c.applied_at && (!plan.at || *c.applied_at < *plan.at)) plan.at = c.applied_at;
  }
  if (when_ready) plan.at.reset();
  for (size_t i = 0; i < tied_.size(); ++i)
    if (suture_due(i, t0, t1)) return {};
  if (events_.tear && t1 > events_.tear->start) return {};
  return plan;
}

bool TopologyEvents::separate(double t0, double t1, const Model& current, const std::vector<Vec3>& x, Model& next,
                              nlohmann::json& sources, ChangeCounts& counts) {
  std::vector<int32_t> faces;
  for (size_t i = 0; i < events_.cuts.size(); ++i) {
    const CutEvent& c = events_.cuts[i];
    if (!(t1 > c.start() && t0 < c.end())) continue;
    BladeSweep sweep;
    c.blade_at(t0, sweep.a0, sweep.b0);
    c.blade_at(t1, sweep.a1, sweep.b1);
    const auto cut = faces_cut_by_blade(sweep, editor_.faces(), current.tet_points, x, editor_.separated());
    if (cut.empty()) continue;
    faces.insert(faces.end(), cut.begin(), cut.end());
    std::vector<int32_t>& record = cut_records_[i].faces;
    record.insert(record.end(), cut.begin(), cut.end());
    std::sort(record.begin(), record.end());
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
  const bool changed = editor_.separate(current, faces, next, counts);
  if (!changed) unopened_faces_ += counts.faces_separated;
  return changed;
}

bool TopologyEvents::tie_sutures_due(double t0, double t1, const Model& base, const std::vector<Vec3>& x, Model& next,
                                     nlohmann::json& sources) {
  std::vector<Suture> added;
  for (size_t i = 0; i < tied_.size(); ++i) {
    if (!suture_due(i, t0, t1)) continue;
    const SutureEvent& event = events_.sutures[i];
    if (x_base_.size() != static_cast<size_t>(base.npoint())) {
      // Points this tick's cut appended sit where their origins are.
      x_base_ = x;
      for (int32_t p = static_cast<int32_t>(x.size()); p < base.npoint(); ++p) x_base_.push_back(x_base_[base.origin[p]]);
    }
    const CutRecord* cut = nullptr;
    for (const CutRecord& r : cut_records_)
      if (r.cut->name == event.along) cut = &r;
    const std::vector<Suture> tied =
        tie_sutures(event, t0, base, x_base_, cut, editor_.faces(), editor_.separated());
    added.insert(added.end(), tied.begin(), tied.end());
    nlohmann::json source = {{"kind", "suture"}, {"sutures", tied.size()}};
    if (!event.along.empty()) source["along"] = event.along;
    double longest = 0;
    for (const Suture& s : tied) longest = std::max(longest, s.length);
    source["longest_m"] = longest;
    sources.push_back(std::move(source));
    tied_[i] = 1;
  }
  x_base_.clear();
  if (added.empty()) return false;
  Model sutured = add_sutures(base, added);  // `base` may be `next`: build first, then move
  next = std::move(sutured);
  return true;
}

bool TopologyEvents::before_tick(double t0, double t1, const Model& current, const std::vector<Vec3>& x,
                                 Model& next) {
  const auto start = std::chrono::steady_clock::now();
  nlohmann::json sources = nlohmann::json::array();
  ChangeCounts counts;
  const bool separated = separate(t0, t1, current, x, next, sources, counts);
  // Sutures due now are tied on the Model this tick's cuts made, if any.
  const bool sutured = tie_sutures_due(t0, t1, separated ? next : current, x, next, sources);
  if (!separated && !sutured) return false;
  std::string kind;
  for (const auto& source : sources) {
    const std::string k = source["kind"];
    if (kind.find(k) == std::string::npos) kind += (kind.empty() ? "" : "+") + k;
  }
  pending_ = {
      {"t", t0},
      {"kind", kind},
      {"sources", sources},
      {"faces_separated", separated ? counts.faces_separated + unopened_faces_ : 0},
      {"points_split", counts.points_split},
      {"points_added", counts.points_added},
      {"springs_added", counts.springs_added},
      {"springs_removed", counts.springs_removed},
      {"sutures_added", next.nsuture() - current.nsuture()},
      {"points", next.npoint()},
      {"springs", next.nspring()},
      {"sutures", next.nsuture()},
      {"model_ms", 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()},
  };
  if (separated) unopened_faces_ = 0;
  return true;
}

double TopologyEvents::guaranteed_step(const Model& previous, const Model& next, const CriticalStepOptions& options) {
  step_check_.update(previous, next);
  return step_check_.guaranteed_step(next, options);
}

void TopologyEvents::changed(const Model& previous, const Model& next, const ChangeTimes& times,
                             double dt_crit_guaranteed, const StabilityReport* full, std::optional<double> applied_t) {
  if (tear_) tear_->model_changed(previous, next);
  if (applied_t) pending_["applied_t"] = *applied_t;
  if (times.prepare_seconds) pending_["backend_prepare_ms"] = 1e3 * *times.prepare_seconds;
  pending_["backend_rebuild_ms"] = 1e3 * times.rebuild_seconds;
  pending_["dt_crit_guaranteed"] = dt_crit_guaranteed;
  pending_["dt_check"] = full ? "power iteration" : "gershgorin";
  if (full) pending_["dt_crit"] = full->dt_crit;
  pending_["dt_check_ms"] = 1e3 * times.check_seconds;
  if (times.check_prepare_seconds) pending_["dt_check_prepare_ms"] = 1e3 * *times.check_prepare_seconds;
  log_.push_back(std::move(pending_));
  pending_ = nlohmann::json();
}

}  // namespace organsim
