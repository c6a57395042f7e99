// The scenario's `tool` section: a sphere, capsule or grasper following
// keyframes (position, orientation, a grasper's jaw gap), push or pull,
// with optional friction.
// GCC 12's AVX-512 intrinsics fill unused operands with undefined values,
// which -Wmaybe-uninitialized reports inside Eigen's stableNorm below once
// the sanitizers are on (a known false positive). Before the first include:
// the headers bring in Eigen.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <nlohmann/json.hpp>

#include <cmath>

#include "core/scenario/scenario_sections.h"

namespace organsim::scenario_detail {

namespace {
// A keyframe's orientation: "orientation": [w, x, y, z] (a unit quaternion;
// normalised, so rounded decimals are fine) or "axis_angle": {"axis": [x, y,
// z], "angle": rad}; identity when neither is given.
Quat parse_orientation(ObjectReader& k) {
  if (k.has("orientation") && k.has("axis_angle"))
    throw k.at("axis_angle").error("give either \"orientation\" or \"axis_angle\", not both");
  if (const nlohmann::json* j = k.get("orientation")) {
    const std::vector<double> q = read_numbers(*j, k.at("orientation"), 4);
    const Quat out(q[0], q[1], q[2], q[3]);
    // A quaternion far from unit length is more likely a mistake (an axis
    // or Euler angles) than rounding.
    if (!(std::abs(out.norm() - 1) < 1e-3))
      throw k.at("orientation").error("expected a unit quaternion [w, x, y, z] (got length " +
                                      std::to_string(out.norm()) + ")");
    return out.normalized();
  }
  if (const nlohmann::json* j = k.get("axis_angle")) {
    const JsonPath at = k.at("axis_angle");
    ObjectReader a(*j, at);
    const Vec3 axis = read_vec3(a.require("axis"), a.at("axis"));
    const double angle = read_number(a.require("angle"), a.at("angle"));
    a.finish();
    const double length = axis.stableNorm();  // no overflow for huge components
    if (!(length > 0) || !std::isfinite(length)) throw a.at("axis").error("expected a non-zero axis [x, y, z]");
    return Quat(Eigen::AngleAxisd(angle, axis / length));
  }
  return Quat::Identity();
}

// A grasper's keyframes: "gap" (m, the distance between its jaws' axes) on
// the first, optional on the others (a keyframe without it keeps the one
// before); refused on any other shape.
std::vector<Keyframe> parse_keyframes(const nlohmann::json& j, const JsonPath& at, bool grasper) {
  if (!j.is_array()) throw at.error("expected an array of {\"t\": s, \"position\": [x, y, z]} (optional \"orientation\": [w, x, y, z])");
  if (j.empty()) throw at.error("expected at least one keyframe");
  std::vector<Keyframe> out;
  for (size_t i = 0; i < j.size(); ++i) {
    const JsonPath kat = at.index(i);
    ObjectReader k(j[i], kat);
    Keyframe f;
    f.t = require_non_negative(read_number(k.require("t"), k.at("t")), k.at("t"));
    f.position = read_vec3(k.require("position"), k.at("position"));
    f.orientation = parse_orientation(k);
    if (k.has("gap") && !grasper) throw k.at("gap").error("only used with \"shape\": \"grasper\"");
    if (auto gap = k.number("gap")) {
      f.gap = require_non_negative(*gap, k.at("gap"));
    } else if (grasper) {
      if (out.empty()) throw k.at("gap").error("expected the grasper's jaw gap (m) on its first keyframe");
      f.gap = out.back().gap;
    }
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
// "friction": {"static": mu_s, "kinetic": mu_k} (mu_k <= mu_s; kinetic
// defaults to static), for surface contact.
Friction parse_friction(const nlohmann::json& j, const JsonPath& at, const ToolSpec& s) {
  if (s.mode != ToolMode::Push || s.contact != ToolContact::Surface)
    throw at.error("friction acts on surface contact (\"mode\": \"push\", \"contact\": \"surface\")");
  ObjectReader f(j, at);
  Friction out;
  out.mu_s = require_positive(read_number(f.require("static"), f.at("static")), f.at("static"));
  out.mu_k = out.mu_s;
  if (auto v = f.number("kinetic")) {
    out.mu_k = require_non_negative(*v, f.at("kinetic"));
    if (out.mu_k > out.mu_s)
      throw f.at("kinetic").error("expected a kinetic coefficient at most the static one (" +
                                  std::to_string(out.mu_s) + ")");
  }
  f.finish();
  return out;
}
}  // namespace

ToolDef parse_tool(const nlohmann::json& j, const JsonPath& at, bool elastic) {
  ObjectReader r(j, at);
  ToolDef tool;
  ToolSpec& s = tool.spec;
  if (auto shape = r.string("shape")) {
    if (*shape == "sphere") {
      s.shape = ToolShape::Sphere;
    } else if (*shape == "capsule") {
      s.shape = ToolShape::Capsule;
    } else if (*shape == "grasper") {
      s.shape = ToolShape::Grasper;
    } else {
      throw r.at("shape").error("expected " + one_of({"sphere", "capsule", "grasper"}) + " (got \"" + *shape + "\")");
    }
  }
  if (auto v = r.number("radius")) s.radius = require_positive(*v, r.at("radius"));
  // A capsule's segment (a grasper's jaws' midline) in the tool frame:
  // "ends": [[x, y, z], [x, y, z]], m.
  if (s.shape != ToolShape::Sphere) {
    const JsonPath eat = r.at("ends");
    const nlohmann::json& ends = r.require("ends");
    if (!ends.is_array() || ends.size() != 2)
      throw eat.error("expected two end points [[x, y, z], [x, y, z]] in the tool frame, m");
    s.end_a = read_vec3(ends[0], eat.index(0));
    s.end_b = read_vec3(ends[1], eat.index(1));
    if (!((s.end_b - s.end_a).norm() > 0))
      throw eat.error("expected two different end points (a capsule of zero length is \"shape\": \"sphere\")");
  } else if (r.has("ends")) {
    throw r.at("ends").error("only used with \"shape\": \"capsule\" or \"grasper\"");
  }
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
  // A pulling tool grasps the points near its origin; a capsule's shape would mean nothing to it.
  if (s.shape != ToolShape::Sphere && s.mode != ToolMode::Push)
    throw r.at("shape").error(std::string("\"") + shape_name(s.shape) + "\" is a pushing tool (\"mode\": \"push\")");
  if (s.shape == ToolShape::Grasper && s.contact != ToolContact::Surface)
    throw r.at("contact").error("a grasper's jaws touch the surface (\"contact\": \"surface\")");
  if (const nlohmann::json* f = r.get("friction")) s.friction = parse_friction(*f, r.at("friction"), s);
  // The layer (a sphere's Hertz law, a capsule's line law) is on by default
  // wherever it applies: a grasper's jaws grip rather than indent, and a
  // material of spring constants has no E for it.
  const bool pushing = s.shape != ToolShape::Grasper && s.mode == ToolMode::Push && s.contact == ToolContact::Surface;
  s.hertz_layer = pushing && elastic;
  if (auto v = r.boolean("hertz_layer")) {
    if (*v && !pushing)
      throw r.at("hertz_layer").error(
          "the sub-cell layer is a pushing sphere's or capsule's surface contact (\"shape\": \"sphere\" or "
          "\"capsule\", \"mode\": \"push\", \"contact\": \"surface\")");
    if (*v && !elastic)
      throw r.at("hertz_layer").error(
          "the sub-cell layer needs the material's young_modulus (a spring_stiffness gives none)");
    s.hertz_layer = *v;
  }
  // Without friction a grasper's jaws only squeeze: it could hold nothing.
  if (s.shape == ToolShape::Grasper && !s.friction.on())
    throw r.at("friction").error("a grasper holds by friction: expected \"friction\": {\"static\": mu_s, \"kinetic\": mu_k}");
  s.keyframes = parse_keyframes(r.require("keyframes"), r.at("keyframes"), s.shape == ToolShape::Grasper);
  r.finish();
  return tool;
}

}  // namespace organsim::scenario_detail
