#include "core/live/session_scenario.h"

#include "core/sweep/field_path.h"

namespace organsim {

nlohmann::json session_scenario(const std::filesystem::path& served_scenario, const std::vector<Keyframe>& keyframes,
                                double duration, const std::string& backend, const std::string& precision,
                                const std::vector<CutEvent>& client_cuts,
                                const std::vector<std::pair<size_t, double>>& scripted_applied) {
  nlohmann::json j = scenario_json_with_absolute_paths(served_scenario);
  // nlohmann writes each double as the shortest text that reads back as the
  // same double, so the times and positions survive the file exactly.
  nlohmann::json frames = nlohmann::json::array();
  for (const Keyframe& k : keyframes)
    frames.push_back({{"t", k.t}, {"position", {k.position.x(), k.position.y(), k.position.z()}}});
  j["tool"]["keyframes"] = frames;
  j["time"]["duration"] = duration;
  // The scenario's one-tick cuts (the n-th "cut" among its events) go in when the session swapped them in.
  for (const auto& [n, applied_at] : scripted_applied) {
    size_t cuts = 0;
    for (nlohmann::json& e : j["events"])
      if (e.contains("cut") && cuts++ == n) e["cut"]["applied_at"] = applied_at;
  }
  // After the scenario's own events: the run adds the client's cuts after them too.
  if (!client_cuts.empty() && !j.contains("events")) j["events"] = nlohmann::json::array();
  const auto vec = [](const Vec3& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  for (const CutEvent& c : client_cuts) {
    nlohmann::json frames = nlohmann::json::array();
    for (const BladeKeyframe& k : c.keyframes) frames.push_back({{"t", k.t}, {"a", vec(k.a)}, {"b", vec(k.b)}});
    nlohmann::json cut = {{"name", c.name}, {"keyframes", frames}};
    if (c.applied_at) cut["applied_at"] = *c.applied_at;
    j["events"].push_back({{"cut", cut}});
  }
  // "backend" may be a bare name; threads, when given, stay (results do not depend on them).
  nlohmann::json b = j.contains("backend") && j["backend"].is_object() ? j["backend"] : nlohmann::json::object();
  b["name"] = backend;
  b["precision"] = precision;
  j["backend"] = b;
  return j;
}

}  // namespace organsim
