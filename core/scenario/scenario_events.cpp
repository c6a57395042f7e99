// The scenario's `events` section: cuts and tears.
#include <nlohmann/json.hpp>

#include <set>

#include "core/scenario/scenario_sections.h"

namespace organsim {

void CutEvent::blade_at(double t, Vec3& a, Vec3& b) const {
  if (t <= keyframes.front().t) {
    a = keyframes.front().a;
    b = keyframes.front().b;
    return;
  }
  for (size_t i = 1; i < keyframes.size(); ++i) {
    const BladeKeyframe& k0 = keyframes[i - 1];
    const BladeKeyframe& k1 = keyframes[i];
    if (t <= k1.t) {
      const double s = (t - k0.t) / (k1.t - k0.t);
      a = k0.a + s * (k1.a - k0.a);
      b = k0.b + s * (k1.b - k0.b);
      return;
    }
  }
  a = keyframes.back().a;
  b = keyframes.back().b;
}

namespace scenario_detail {

namespace {

CutEvent parse_cut(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  CutEvent cut;
  if (auto n = r.string("name")) {
    if (n->empty()) throw r.at("name").error("expected a non-empty name");
    cut.name = *n;
  }
  const nlohmann::json& k = r.require("keyframes");
  const JsonPath kat = r.at("keyframes");
  if (!k.is_array() || k.size() < 2)
    throw kat.error("expected an array of at least two {\"t\": s, \"a\": [x, y, z], \"b\": [x, y, z]}");
  for (size_t i = 0; i < k.size(); ++i) {
    ObjectReader f(k[i], kat.index(i));
    BladeKeyframe b;
    b.t = require_non_negative(read_number(f.require("t"), f.at("t")), f.at("t"));
    b.a = read_vec3(f.require("a"), f.at("a"));
    b.b = read_vec3(f.require("b"), f.at("b"));
    f.finish();
    if (!((b.b - b.a).norm() > 0)) throw kat.index(i).error("expected a blade of non-zero length (a != b)");
    if (!cut.keyframes.empty() && !(b.t > cut.keyframes.back().t))
      throw f.at("t").error("keyframes must be sorted by strictly increasing t (" + std::to_string(b.t) + " after " +
                            std::to_string(cut.keyframes.back().t) + ")");
    cut.keyframes.push_back(b);
  }
  r.finish();
  return cut;
}

TearEvent parse_tear(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  TearEvent tear;
  if (auto v = r.number("start")) tear.start = require_non_negative(*v, r.at("start"));
  tear.strain = require_positive(read_number(r.require("strain"), r.at("strain")), r.at("strain"));
  if (auto v = r.integer("ticks")) {
    if (*v < 1 || *v > 1'000'000) throw r.at("ticks").error("expected an integer >= 1 (got " + std::to_string(*v) + ")");
    tear.ticks = static_cast<int32_t>(*v);
  }
  if (auto v = r.integer("max_per_tick")) {
    if (*v < 1 || *v > 1'000'000)
      throw r.at("max_per_tick").error("expected an integer >= 1 (got " + std::to_string(*v) + ")");
    tear.max_per_tick = static_cast<int32_t>(*v);
  }
  r.finish();
  return tear;
}

}  // namespace

EventsDef parse_events(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_array()) throw at.error("expected an array of events ({\"cut\"|\"tear\": {...}})");
  EventsDef events;
  std::set<std::string> names;
  for (size_t i = 0; i < j.size(); ++i) {
    const JsonPath eat = at.index(i);
    ObjectReader r(j[i], eat);
    if (j[i].size() != 1) throw eat.error("expected exactly one of \"cut\" or \"tear\"");
    if (const nlohmann::json* c = r.get("cut")) {
      CutEvent cut = parse_cut(*c, eat.field("cut"));
      if (cut.name.empty()) cut.name = "cut" + std::to_string(events.cuts.size());
      if (!names.insert(cut.name).second) throw eat.field("cut").field("name").error("duplicate cut name \"" + cut.name + "\"");
      events.cuts.push_back(std::move(cut));
    } else if (const nlohmann::json* t = r.get("tear")) {
      if (events.tear) throw eat.error("only one \"tear\" event per scenario");
      events.tear = parse_tear(*t, eat.field("tear"));
    }
    r.finish();  // names the unknown event kind
  }
  return events;
}

}  // namespace scenario_detail

}  // namespace organsim
