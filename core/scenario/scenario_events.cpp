// The scenario's `events` section: cuts, tears and sutures.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
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
  if (auto v = r.number("applied_at")) {
    if (cut.keyframes.size() != 2)
      throw r.at("applied_at").error("is for a cut over one tick (exactly two keyframes, as organsim serve records)");
    if (!(*v >= cut.keyframes.front().t))
      throw r.at("applied_at").error("expected a time >= the first keyframe's t (" +
                                     std::to_string(cut.keyframes.front().t) + " s)");
    cut.applied_at = *v;
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

SutureEvent parse_suture(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  SutureEvent s;
  s.where = at.file.empty() ? at.path : at.file + ": " + at.path;
  s.t = require_non_negative(read_number(r.require("t"), r.at("t")), r.at("t"));
  s.stiffness = require_positive(read_number(r.require("stiffness"), r.at("stiffness")), r.at("stiffness"));
  const nlohmann::json* pairs = r.get("pairs");
  const std::optional<std::string> along = r.string("along");
  if ((pairs != nullptr) == along.has_value())
    throw at.error("expected exactly one of \"pairs\" ([[i, j], ...], point ids) or \"along\" (a cut's name)");
  if (pairs) {
    const JsonPath pat = r.at("pairs");
    if (!pairs->is_array() || pairs->empty()) throw pat.error("expected a non-empty array of point id pairs [[i, j], ...]");
    for (size_t k = 0; k < pairs->size(); ++k) {
      const nlohmann::json& p = (*pairs)[k];
      if (!p.is_array() || p.size() != 2) throw pat.index(k).error("expected a pair of point ids [i, j]");
      std::array<int32_t, 2> ids{};
      for (size_t e = 0; e < 2; ++e) {
        const int64_t id = read_integer(p[e], pat.index(k).index(e));
        if (id < 0 || id > INT32_MAX)
          throw pat.index(k).index(e).error("expected a point id >= 0 (got " + std::to_string(id) + ")");
        ids[e] = static_cast<int32_t>(id);
      }
      if (ids[0] == ids[1])
        throw pat.index(k).error("a suture joins two different points (got " + std::to_string(ids[0]) + " twice)");
      s.pairs.push_back(ids);
    }
    for (const char* key : {"spacing", "max_distance"})
      if (r.has(key)) throw r.at(key).error("only with \"along\" (explicit pairs are tied as given)");
  } else {
    if (along->empty()) throw r.at("along").error("expected a cut's name");
    s.along = *along;
    s.spacing = require_positive(read_number(r.require("spacing"), r.at("spacing")), r.at("spacing"));
    s.max_distance =
        require_positive(read_number(r.require("max_distance"), r.at("max_distance")), r.at("max_distance"));
  }
  if (auto v = r.number("length")) s.length = require_non_negative(*v, r.at("length"));
  if (auto v = r.number("rate")) s.rate = require_non_negative(*v, r.at("rate"));
  if (auto v = r.number("min_length")) s.min_length = require_non_negative(*v, r.at("min_length"));
  r.finish();
  return s;
}

}  // namespace

EventsDef parse_events(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_array()) throw at.error("expected an array of events ({\"cut\"|\"tear\"|\"suture\": {...}})");
  EventsDef events;
  std::set<std::string> names;
  for (size_t i = 0; i < j.size(); ++i) {
    const JsonPath eat = at.index(i);
    ObjectReader r(j[i], eat);
    if (j[i].size() != 1) throw eat.error("expected exactly one of \"cut\", \"tear\" or \"suture\"");
    if (const nlohmann::json* c = r.get("cut")) {
      CutEvent cut = parse_cut(*c, eat.field("cut"));
      if (cut.name.empty()) cut.name = "cut" + std::to_string(events.cuts.size());
      if (!names.insert(cut.name).second) throw eat.field("cut").field("name").error("duplicate cut name \"" + cut.name + "\"");
      events.cuts.push_back(std::move(cut));
    } else if (const nlohmann::json* t = r.get("tear")) {
      if (events.tear) throw eat.error("only one \"tear\" event per scenario");
      events.tear = parse_tear(*t, eat.field("tear"));
    } else if (const nlohmann::json* u = r.get("suture")) {
      events.sutures.push_back(parse_suture(*u, eat.field("suture")));
    }
    r.finish();  // names the unknown event kind
  }
  // Sutures along a cut: the cut exists (anywhere in the list) and is done.
  for (size_t i = 0, k = 0; i < j.size(); ++i) {
    if (!j[i].contains("suture")) continue;
    const SutureEvent& s = events.sutures[k++];
    if (s.along.empty()) continue;
    const JsonPath fat = at.index(i).field("suture").field("along");
    const auto cut = std::find_if(events.cuts.begin(), events.cuts.end(), [&](const CutEvent& c) { return c.name == s.along; });
    if (cut == events.cuts.end()) {
      std::string names;
      for (const CutEvent& c : events.cuts) names += (names.empty() ? "" : ", ") + ("\"" + c.name + "\"");
      throw fat.error("no cut named \"" + s.along + "\" (cuts: " + (names.empty() ? "none" : names) + ")");
    }
    if (s.t < cut->end())
      throw fat.error("the cut \"" + s.along + "\" ends at t = " + std::to_string(cut->end()) +
                      " s; sutures along it need t >= that (got " + std::to_string(s.t) + ")");
  }
  return events;
}

}  // namespace scenario_detail

}  // namespace organsim
