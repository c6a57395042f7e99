#include "core/live/live_session.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/live/latency_stats.h"
#include "core/model/model.h"
#include "core/sim/contact_stiffness.h"
#include "core/util/format.h"

namespace organsim {

namespace {

double seconds(LiveClock::duration d) { return std::chrono::duration<double>(d).count(); }

LiveClock::duration from_seconds(double s) {
  return std::chrono::duration_cast<LiveClock::duration>(std::chrono::duration<double>(s));
}

std::string format_vec(const Vec3& v) {
  std::string s("[");  // appended, not "[" + ...: gcc 12 warns falsely (-Wrestrict) on that
  s.append(format_number(v.x())).append(", ").append(format_number(v.y())).append(", ").append(format_number(v.z()));
  return s.append("]");
}

std::string ms(double s) { return format_number(s * 1e3, "%.3g") + " ms"; }

// As the reply latency, and how many wake-ups came over 0.25, 0.5 and 1 ms
// late: a tick that costs c of its T is late after a wake-up over T - c late
// (docs/live.md, "Latency measured").
nlohmann::json wake_up_json(std::vector<double>& late) {
  nlohmann::json j = latency_json(summarise_latency(late));
  for (const auto& over : {std::pair{"over_0.25_ms", 0.25e-3}, {"over_0.5_ms", 0.5e-3}, {"over_1_ms", 1e-3}}) {
    const double limit = over.second;
    j[over.first] = std::count_if(late.begin(), late.end(), [limit](double v) { return v > limit; });
  }
  return j;
}

}  // namespace

bool sweeps_one_tick(const CutEvent& cut, double tick) {
  if (cut.keyframes.size() != 2 || cut.applied_at || cut.when_ready || !(tick > 0)) return false;
  // The run loop's tick i is [i tick, (i + 1) tick] (those products), active
  // for the cut when t1 > start and t0 < end. The first such tick: the
  // smallest i with t1 > start; the next is active too unless its t0 >= end.
  int64_t i = std::max<int64_t>(0, static_cast<int64_t>(std::floor(cut.start() / tick)) - 2);
  while (static_cast<double>(i + 1) * tick <= cut.start()) ++i;
  return static_cast<double>(i + 1) * tick >= cut.end();
}

std::vector<std::pair<size_t, CutEvent>> take_one_tick_cuts(EventsDef& events, double tick) {
  std::vector<std::pair<size_t, CutEvent>> taken;
  std::vector<CutEvent> kept;
  for (size_t i = 0; i < events.cuts.size(); ++i) {
    if (sweeps_one_tick(events.cuts[i], tick)) taken.emplace_back(i, events.cuts[i]);
    else kept.push_back(events.cuts[i]);
  }
  events.cuts = std::move(kept);
  std::stable_sort(taken.begin(), taken.end(),
                   [](const auto& a, const auto& b) { return a.second.start() < b.second.start(); });
  return taken;
}

LiveSession::LiveSession(LiveLink& link, LiveOptions options)
    : link_(link), o_(std::move(options)), refusals_(o_.log), command_refusals_(o_.log), device_(o_.device), current_(o_.start) {
  if (!o_.clock) o_.clock = [] { return LiveClock::now(); };
  keyframes_.push_back({0.0, o_.start});
  scripted_applied_at_.resize(o_.scripted_cuts.size());
}

std::optional<Vec3> LiveSession::tool_at_end_of(int64_t tick, double t_end) {
  const auto stopped = [&] {
    if (o_.stop && o_.stop->load()) stopped_by_ = "SIGINT";
    return !stopped_by_.empty();
  };
  if (stopped()) return std::nullopt;
  if (tick == 0) {
    static const std::atomic<bool> never{false};
    if (!link_.wait_for_client(o_.stop ? *o_.stop : never)) {
      stopped_by_ = "SIGINT";
      return std::nullopt;
    }
    start_ = last_status_ = o_.clock();
  }
  // The run loop's t0 for this tick is the last tick's t1, the same double.
  const double t_start = tick == 0 ? 0.0 : end_time_;
  const LiveClock::time_point scheduled = start_ + from_seconds(t_start);
  early_ = scheduled - from_seconds(o_.tick);
  wait_until(early_);
  if (!pending_) wait_until(scheduled);
  if (stopped()) return std::nullopt;
  apply_pending(tick, t_start, t_end);
  // A scripted cut at its tick; a client's waits until no cut is in flight
  // (and is made at the pose of the tick it goes out with).
  const auto& scripted = o_.scripted_cuts;
  if (next_scripted_ < scripted.size() && scripted[next_scripted_].second.start() < t_end) {
    cut_this_tick_ = scripted[next_scripted_].second;
    cut_this_tick_->when_ready = true;
    in_flight_.emplace_back(true, next_scripted_++);
  } else if (cut_requested_ && in_flight_.empty()) {
    make_cut(tick, t_start, t_end);
  }
  end_time_ = t_end;
  return current_;
}

void LiveSession::wait_until(LiveClock::time_point deadline) {
  const LiveClock::time_point before = o_.clock();
  pose_started_at_.reset();
  link_.receive_until(deadline, *this);
  if (before >= deadline) return;  // behind the clock: no wait
  // The loop ran again at the pose that started the tick or, without one,
  // now. A pose before the deadline ended the wait early (no wake-up to
  // record); one read in the link's last pass came after the clock woke it.
  const LiveClock::time_point woke = pose_started_at_.value_or(o_.clock());
  if (woke >= deadline) wake_up_seconds_.push_back(seconds(woke - deadline));
}

std::optional<CutEvent> LiveSession::cut_for_tick() {
  std::optional<CutEvent> cut;
  cut.swap(cut_this_tick_);
  return cut;
}

void LiveSession::cut_applied(double t0) {
  if (in_flight_.empty()) return;
  const auto [is_scripted, i] = in_flight_.front();
  in_flight_.pop_front();
  // The tick that starts now (ticks_ were served before it).
  if (is_scripted) {
    scripted_applied_at_[i] = t0;
    if (o_.log) {
      const auto& [index, cut] = o_.scripted_cuts[i];
      *o_.log << "organsim serve: the scenario's cut " << index;
      if (!cut.name.empty()) *o_.log << " (\"" << cut.name << "\")";
      *o_.log << " in the model from tick " << ticks_ << "\n";
    }
    return;
  }
  cuts_[i].applied_at = t0;
  cut_log_[i]["applied_tick"] = ticks_;
  if (o_.log) *o_.log << "organsim serve: " << cuts_[i].name << " in the model from tick " << ticks_ << "\n";
}

std::vector<std::pair<size_t, double>> LiveSession::scripted_applied() const {
  std::vector<std::pair<size_t, double>> out;
  // A cut still being built: no tick of the replay starts at the session's end (as cuts()).
  for (size_t i = 0; i < next_scripted_; ++i)
    out.emplace_back(o_.scripted_cuts[i].first, scripted_applied_at_[i].value_or(end_time_));
  return out;
}

std::vector<CutEvent> LiveSession::cuts() const {
  std::vector<CutEvent> out = cuts_;
  for (CutEvent& c : out) {
    // A cut still being built: no tick of the replay starts at the session's end.
    if (!c.applied_at) c.applied_at = end_time_;
    c.when_ready = false;
  }
  return out;
}

void LiveSession::on_text(const ClientText& text) {
  ParsedCommand parsed = parse_client_command(text.text);
  if (auto* why = std::get_if<std::string>(&parsed)) {
    command_refusals_.refuse("unknown_command", text.client, "STRING of device \"" + text.device + "\": " + *why);
    return;
  }
  if (!current_matrix_ && !pending_) {
    command_refusals_.refuse("cut_without_pose", text.client, "CUT before any tool pose (the cut is made at the tool's pose)");
    return;
  }
  if (cut_requested_ || !in_flight_.empty()) {
    command_refusals_.refuse("cut_busy", text.client,
                             "CUT while the previous cut is not in the model yet (it is being built off the tick's path)");
    return;
  }
  cut_requested_.emplace(std::get<CutCommand>(parsed), text);
}

void LiveSession::make_cut(int64_t tick, double t_start, double t_end) {
  const auto [command, text] = *cut_requested_;
  cut_requested_.reset();
  // The pose this tick moves the tool to: a CUT sent after a pose cuts at that pose.
  const CutBlade blade = cut_blade(o_.frame, *current_matrix_, command);
  if (!blade.a0.allFinite() || !blade.b0.allFinite() || !blade.a1.allFinite() || !blade.b1.allFinite()) {
    command_refusals_.refuse("cut_degenerate", text.client, "CUT at a pose whose rotation has a zero x or z axis");
    return;
  }
  CutEvent cut;
  for (size_t n = cuts_.size() + 1; cut.name.empty() || std::count(o_.cut_names.begin(), o_.cut_names.end(), cut.name); ++n)
    cut.name = "client_cut" + std::to_string(n);
  cut.keyframes = {{t_start, blade.a0, blade.b0}, {t_end, blade.a1, blade.b1}};
  cut.when_ready = true;
  cuts_.push_back(cut);
  cut_this_tick_ = cut;
  in_flight_.emplace_back(false, cuts_.size() - 1);
  const auto vec = [](const Vec3& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  cut_log_.push_back({{"tick", tick},
                      {"name", cut.name},
                      {"received_s", seconds(text.received - start_)},
                      {"client", text.client},
                      {"text", printable_text(text.text)},
                      {"blade_start", {vec(blade.a0), vec(blade.b0)}},
                      {"blade_end", {vec(blade.a1), vec(blade.b1)}}});
  if (o_.log) *o_.log << "organsim serve: " << cut.name << " from " << text.client << " at tick " << tick << "\n";
}

bool LiveSession::on_pose(const ClientPose& pose) {
  ++poses_received_;
  if (device_.empty()) {
    device_ = pose.device;
    if (o_.log) *o_.log << "organsim serve: following device \"" << device_ << "\" from " << pose.client << "\n";
  }
  if (pose.device != device_) {
    refusals_.refuse("other_device", pose.client,
                     "TRANSFORM of device \"" + pose.device + "\" (following \"" + device_ + "\"; --device picks one)");
    return false;
  }
  for (double v : pose.matrix) {
    if (!std::isfinite(v)) {
      refusals_.refuse("not_finite", pose.client, "TRANSFORM with a NaN or infinite entry");
      return false;
    }
  }
  const Vec3 p = o_.frame.scene_position(pose.matrix);
  if (!o_.scene.contains(p)) {
    refusals_.refuse("outside_scene", pose.client,
                     "pose at " + format_vec(p) + " m in the scene, outside the box " + format_vec(o_.scene.lo) +
                         " .. " + format_vec(o_.scene.hi) + " m (check --client-units and --client-transform)");
    return false;
  }
  if (pending_) ++superseded_;
  pending_ = pose;
  pending_position_ = p;
  const LiveClock::time_point now = o_.clock();
  if (now < early_) return false;
  if (!pose_started_at_) pose_started_at_ = now;
  return true;
}

void LiveSession::apply_pending(int64_t tick, double t_start, double t_end) {
  tick_pose_received_.reset();
  if (!pending_) return;
  tick_pose_received_ = pending_->received;
  applied_.push_back({tick, seconds(pending_->received - start_), *pending_});
  if (pending_position_ != current_) {
    // Hold the last pose to the start of this tick, then move to the new one
    // at its end: exactly what this tick stepped (tool_from, tool_to).
    if (keyframes_.back().t < t_start) keyframes_.push_back({t_start, current_});
    keyframes_.push_back({t_end, pending_position_});
    current_ = pending_position_;
  }
  current_matrix_ = pending_->matrix;
  pending_.reset();
}

void LiveSession::on_tick(const Model& model, Backend& backend, const TickInfo& info) {
  // The contact's stiffness at the end of the tick the reaction is of (on
  // the GL backend the one before: its positions kept on the GPU, so that
  // this never waits for the tick in flight); only in contact (a copy of
  // the positions and one pass over the surface).
  // A window of latency + 1 entries, shifted in place: no allocation per tick.
  const size_t latency = static_cast<size_t>(backend.reaction_latency_ticks());
  if (recent_ends_.size() <= latency) {
    recent_ends_.push_back({info.t, info.tool_center});
  } else {
    std::move(recent_ends_.begin() + 1, recent_ends_.end(), recent_ends_.begin());
    recent_ends_.back() = {info.t, info.tool_center};
  }
  Mat3 stiffness = info.held_stiffness;  // a pulling tool's, while it holds
  if (info.reaction.contacts > 0 && o_.tool.mode == ToolMode::Push) {
    // CPU work, timed on the steady clock whatever the session's clock is.
    const LiveClock::time_point begin = LiveClock::now();
    backend.reaction_positions(stiffness_positions_);
    stiffness = tool_contact_stiffness(model, stiffness_positions_, o_.tool, recent_ends_.front().second,
                                       o_.tool.hertz_layer ? &contact_layer_ : nullptr);
    stiffness_seconds_.push_back(seconds(LiveClock::now() - begin));
  }
  link_.send_reaction(info.tick, info.t, o_.frame.client_direction(info.reaction.force),
                      o_.frame.client_direction(info.reaction.torque), o_.frame.client_matrix(stiffness));
  const LiveClock::time_point now = o_.clock();
  note_tick_wall(info.tick, seconds(now - (ticks_ == 0 ? start_ : last_reply_)));
  last_reply_ = now;
  ++ticks_;
  if (now > start_ + from_seconds(info.t)) ++late_;
  if (tick_pose_received_) latencies_.push_back(seconds(now - *tick_pose_received_));
  wall_seconds_ = seconds(now - start_);
  maybe_status(now);
  if (recent_ends_.size() == latency + 1) maybe_surface(backend, recent_ends_.front().first, now);
}

void LiveSession::on_start(const Model& model, Backend& /*backend*/) {
  find_surface(model);
  if (o_.tool.hertz_layer) contact_layer_ = contact_layer(model);
}

void LiveSession::on_topology_changed(const Model& next, Backend& /*backend*/) {
  find_surface(next);
  if (o_.tool.hertz_layer) contact_layer_ = contact_layer(next);
}

void LiveSession::find_surface(const Model& model) {
  surface_points_.clear();
  surface_triangles_.clear();
  if (o_.surface_rate <= 0) return;
  std::vector<int32_t> index(static_cast<size_t>(model.npoint()), -1);
  // Model::surface is the boundary every version extracted when it was made
  // (off the tick's path for a client's cut), so a change costs the tick
  // only this pass over its triangles.
  for (const Tri& f : model.surface) {
    Tri g;
    for (int k = 0; k < 3; ++k) {
      int32_t& i = index[static_cast<size_t>(f[static_cast<size_t>(k)])];
      if (i < 0) {
        i = static_cast<int32_t>(surface_points_.size());
        surface_points_.push_back(f[static_cast<size_t>(k)]);
      }
      g[static_cast<size_t>(k)] = i;
    }
    surface_triangles_.push_back(g);
  }
}

void LiveSession::maybe_surface(Backend& backend, double t, LiveClock::time_point now) {
  if (o_.surface_rate <= 0 || surface_points_.empty() || seconds(now - last_surface_) < 1.0 / o_.surface_rate) return;
  last_surface_ = now;
  backend.reaction_positions(positions_);  // the reaction's tick: never waits for the tick in flight
  surface_client_.resize(surface_points_.size());
  for (size_t k = 0; k < surface_points_.size(); ++k)
    surface_client_[k] = o_.frame.client_position(positions_[static_cast<size_t>(surface_points_[k])]);
  link_.send_surface(t, surface_client_, surface_triangles_);
  ++surfaces_;
}

void LiveSession::maybe_status(LiveClock::time_point now) {
  if (!o_.status || seconds(now - last_status_) < o_.status_interval) return;
  std::vector<double> window(latencies_.begin() + static_cast<std::ptrdiff_t>(status_latencies_), latencies_.end());
  const LatencySummary l = summarise_latency(window);
  std::string line = "serve: t = " + format_number(end_time_, "%.1f") + " s, " + std::to_string(ticks_) + " ticks (" +
                     std::to_string(late_ - status_late_) + " of the last " + std::to_string(ticks_ - status_ticks_) +
                     " late), real-time factor " + format_number(end_time_ / wall_seconds_, "%.2f");
  if (l.count > 0)
    line += ", latency median " + ms(l.median) + ", p99 " + ms(l.p99) + ", max " + ms(l.max);
  else
    line += ", no poses";
  line += ", " + std::to_string(refusals_.total() + command_refusals_.total()) + " refused";
  o_.status(line);
  last_status_ = now;
  status_ticks_ = ticks_;
  status_late_ = late_;
  status_latencies_ = latencies_.size();
}

void LiveSession::note_tick_wall(int64_t tick, double seconds) {
  constexpr size_t kKept = 5;
  if (slowest_.size() == kKept && !(seconds > slowest_.back().second)) return;
  if (slowest_.size() == kKept) slowest_.pop_back();
  const auto at = std::find_if(slowest_.begin(), slowest_.end(), [&](const auto& s) { return seconds > s.second; });
  slowest_.insert(at, {tick, seconds});
}

void LiveSession::add_meta(nlohmann::json& extra) const {
  std::vector<double> all(latencies_.begin(), latencies_.end());
  std::vector<double> stiffness(stiffness_seconds_.begin(), stiffness_seconds_.end());
  std::vector<double> wake_up(wake_up_seconds_.begin(), wake_up_seconds_.end());
  nlohmann::json poses = nlohmann::json::array();
  for (const AppliedPose& a : applied_) {
    poses.push_back({{"tick", a.tick},
                     {"received_s", a.received},
                     {"client", a.pose.client},
                     {"device", a.pose.device},
                     {"matrix", a.pose.matrix}});
  }
  nlohmann::json m = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) m.push_back({o_.frame.to_scene(r, 0), o_.frame.to_scene(r, 1), o_.frame.to_scene(r, 2), o_.frame.to_scene(r, 3)});
  nlohmann::json slowest = nlohmann::json::array();
  for (const auto& [tick, s] : slowest_) slowest.push_back({{"tick", tick}, {"ms", 1e3 * s}});
  extra["live"] = {
      {"ticks", ticks_},
      {"late_ticks", late_},
      {"slowest_ticks", slowest},
      {"latency", latency_json(summarise_latency(all))},
      {"reply_stiffness", latency_json(summarise_latency(stiffness))},
      {"wake_up", wake_up_json(wake_up)},
      {"real_time_factor", wall_seconds_ > 0 ? end_time_ / wall_seconds_ : 0.0},
      {"wall_seconds", wall_seconds_},
      {"device", device_},
      {"client_metres_per_unit", o_.frame.metres_per_unit},
      {"client_transform", m},
      {"poses_received", poses_received_},
      {"poses_applied", applied_.size()},
      {"poses_superseded", superseded_},
      {"poses_refused", refusals_.counts()},
      {"stopped_by", stopped_by_},
      {"surfaces_sent", surfaces_},
      {"commands_refused", command_refusals_.counts()},
      {"cuts", cut_log_},
      {"link", link_.report()},
      {"applied_poses", poses},
  };
}

}  // namespace organsim
