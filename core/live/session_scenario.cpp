#include "core/live/session_scenario.h"

#include "core/sweep/field_path.h"

namespace organsim {

nlohmann::json session_scenario(const std::filesystem::path& served_scenario, const std::vector<Keyframe>& keyframes,
                                double duration, const std::string& backend, const std::string& precision) {
  nlohmann::json j = scenario_json_with_absolute_paths(served_scenario);
  // nlohmann writes each double as the shortest text that reads back as the
  // same double, so the times and positions survive the file exactly.
  nlohmann::json frames = nlohmann::json::array();
  for (const Keyframe& k : keyframes)
    frames.push_back({{"t", k.t}, {"position", {k.position.x(), k.position.y(), k.position.z()}}});
  j["tool"]["keyframes"] = frames;
  j["time"]["duration"] = duration;
  // "backend" may be a bare name; threads, when given, stay (results do not depend on them).
  nlohmann::json b = j.contains("backend") && j["backend"].is_object() ? j["backend"] : nlohmann::json::object();
  b["name"] = backend;
  b["precision"] = precision;
  j["backend"] = b;
  return j;
}

}  // namespace organsim
