#include "core/io/force_log.h"

#include <ostream>

#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

void ForceSamples::reserve(size_t n) {
  t.reserve(n);
  force.reserve(n);
  torque.reserve(n);
  tool_position.reserve(n);
  contacts.reserve(n);
}

void ForceSamples::push(double time, const Vec3& f, const Vec3& tq, const Vec3& tool, int32_t ncontact) {
  t.push_back(time);
  force.push_back(f);
  torque.push_back(tq);
  tool_position.push_back(tool);
  contacts.push_back(ncontact);
}

namespace {
nlohmann::json vec3_column(const std::vector<Vec3>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (const Vec3& p : v) a.push_back({p.x(), p.y(), p.z()});
  return a;
}
}  // namespace

nlohmann::json force_log_json(const ForceLogMeta& meta, const ForceSamples& samples) {
  nlohmann::json m = {
      {"organsim_version", ORGANSIM_VERSION},
      {"scenario", meta.scenario},
      {"backend", meta.backend},
      {"device", meta.device},
      {"precision", meta.precision},
      {"reaction_latency_ticks", meta.reaction_latency_ticks},
      {"points", meta.points},
      {"springs", meta.springs},
      {"tets", meta.tets},
      {"fixed_points", meta.fixed_points},
      {"dt", meta.dt},
      {"substeps", meta.substeps},
      {"tick", meta.dt * meta.substeps},
      {"duration", meta.duration},
      {"samples", samples.size()},
      {"wall_seconds", meta.wall_seconds},
      {"steps_per_second", meta.steps_per_second},
      {"real_time_factor", meta.real_time_factor},
      {"completed", meta.completed},
      {"stop_reason", meta.stop_reason},
      {"units", {{"t", "s"}, {"force", "N"}, {"torque", "N m"}, {"tool_position", "m"}, {"contacts", "points"}}},
  };
  for (const auto& item : meta.extra.items()) m[item.key()] = item.value();
  nlohmann::json columns = {{"t", samples.t},
                             {"force", vec3_column(samples.force)},
                             {"torque", vec3_column(samples.torque)},
                             {"tool_position", vec3_column(samples.tool_position)},
                             {"contacts", samples.contacts}};
  if (!samples.grip.empty()) {
    columns["grip"] = samples.grip;
    m["units"]["grip"] = "N";
  }
  if (!samples.jaw_gap.empty()) {
    columns["jaw_gap"] = samples.jaw_gap;
    m["units"]["jaw_gap"] = "m";
  }
  return {{"meta", std::move(m)}, {"samples", std::move(columns)}};
}

void write_force_log(const std::filesystem::path& path, const ForceLogMeta& meta,
                     const ForceSamples& samples) {
  // Serialise before touching the file system so a serialisation error leaves nothing.
  const std::string text = force_log_json(meta, samples).dump(1);
  write_file_atomically(path, [&](std::ostream& out) { out << text << "\n"; });
}

}  // namespace organsim
