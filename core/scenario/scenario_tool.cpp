// The scenario's `tool` section: a sphere following keyframes, push or pull.
#include <nlohmann/json.hpp>

#include "core/scenario/scenario_sections.h"

namespace organsim::scenario_detail {

namespace {
std::vector<Keyframe> parse_keyframes(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_array()) throw at.error("expected an array of {\"t\": s, \"position\": [x, y, z]}");
  if (j.empty()) throw at.error("expected at least one keyframe");
  std::vector<Keyframe> out;
  for (size_t i = 0; i < j.size(); ++i) {
    const JsonPath kat = at.index(i);
    ObjectReader k(j[i], kat);
    Keyframe f;
    f.t = require_non_negative(read_number(k.require("t"), k.at("t")), k.at("t"));
    f.position = read_vec3(k.require("position"), k.at("position"));
    k.finish();
    // Interpolation needs strictly increasing times.
    if (!out.empty() && !(f.t > out.back().t)) {
      throw k.at("t").error("keyframes must be sorted by strictly increasing t (" + std::to_string(f.t) +
                            " after " + std::to_string(out.back().t) + ")");
    }
    out.push_back(f);
  }
  return out;
}
}  // namespace

ToolDef parse_tool(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  ToolDef tool;
  ToolSpec& s = tool.spec;
  if (auto shape = r.string("shape")) {
    if (*shape != "sphere") throw r.at("shape").error("expected \"sphere\" (the only tool shape so far; got \"" + *shape + "\")");
  }
  if (auto v = r.number("radius")) s.radius = require_positive(*v, r.at("radius"));
  if (auto v = r.number("contact_stiffness")) s.contact_stiffness = require_positive(*v, r.at("contact_stiffness"));
  if (auto mode = r.string("mode")) {
    if (*mode == "push") {
      s.mode = ToolMode::Push;
    } else if (*mode == "pull") {
      s.mode = ToolMode::Pull;
    } else {
      throw r.at("mode").error("expected " + one_of({"push", "pull"}) + " (got \"" + *mode + "\")");
    }
  }
  if (auto contact = r.string("contact")) {
    if (s.mode != ToolMode::Push) throw r.at("contact").error("only used with \"mode\": \"push\"");
    if (*contact == "surface") {
      s.contact = ToolContact::Surface;
    } else if (*contact == "points") {
      s.contact = ToolContact::Points;
    } else {
      throw r.at("contact").error("expected " + one_of({"surface", "points"}) + " (got \"" + *contact + "\")");
    }
  }
  // Grasp settings mean nothing to a pushing tool: say so instead of ignoring them.
  for (const char* key : {"grasp_radius", "grasp_time", "release_time"}) {
    if (s.mode != ToolMode::Pull && r.has(key)) throw r.at(key).error("only used with \"mode\": \"pull\"");
  }
  if (auto v = r.number("grasp_radius")) s.grasp_radius = require_positive(*v, r.at("grasp_radius"));
  if (auto v = r.number("grasp_time")) s.grasp_time = require_non_negative(*v, r.at("grasp_time"));
  if (auto v = r.number("release_time")) {
    if (!(*v > s.grasp_time)) throw r.at("release_time").error("expected a time after grasp_time (" + std::to_string(s.grasp_time) + " s)");
    s.release_time = *v;
  }
  s.keyframes = parse_keyframes(r.require("keyframes"), r.at("keyframes"));
  r.finish();
  return tool;
}

}  // namespace organsim::scenario_detail
