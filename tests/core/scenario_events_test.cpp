// The scenario's `events` section: values as documented, strict errors that
// name the JSON path, and blade interpolation.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/scenario/scenario.h"
#include "core/util/error.h"

namespace organsim {
namespace scenario_events_test {
namespace {

using nlohmann::json;

json with_events(const json& events) {
  json j = json::parse(R"({"mesh": {"tet": "cube.mesh"}})");
  j["events"] = events;
  return j;
}

std::string error_of(const json& events) {
  try {
    parse_scenario(with_events(events), "/data", "scene.json");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Scenario) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "parsed without error: " << events.dump();
  return "";
}

const json kCut = json::parse(R"({"cut": {"name": "incision", "keyframes": [
    {"t": 0.1, "a": [0, 0, 1], "b": [0, 1, 1]},
    {"t": 0.3, "a": [0, 0, 0], "b": [0, 1, 0]}]}})");

TEST(ScenarioEvents, NoEventsMeansNoTopology) {
  const Scenario s = parse_scenario(json::parse(R"({"mesh": {"tet": "cube.mesh"}})"), "/data", "scene.json");
  EXPECT_FALSE(s.events.any());
}

TEST(ScenarioEvents, CutAndTearAsWritten) {
  const Scenario s = parse_scenario(
      with_events(json::array({kCut, json::parse(R"({"tear": {"start": 0.2, "strain": 0.5, "ticks": 2, "max_per_tick": 8}})")})),
      "/data", "scene.json");
  ASSERT_EQ(s.events.cuts.size(), 1u);
  const CutEvent& c = s.events.cuts[0];
  EXPECT_EQ(c.name, "incision");
  EXPECT_DOUBLE_EQ(c.start(), 0.1);
  EXPECT_DOUBLE_EQ(c.end(), 0.3);
  Vec3 a, b;
  c.blade_at(0.2, a, b);  // halfway: linear interpolation
  EXPECT_TRUE(a.isApprox(Vec3(0, 0, 0.5)));
  EXPECT_TRUE(b.isApprox(Vec3(0, 1, 0.5)));
  c.blade_at(5.0, a, b);  // held at the last keyframe
  EXPECT_EQ(a, Vec3(0, 0, 0));
  ASSERT_TRUE(s.events.tear.has_value());
  EXPECT_DOUBLE_EQ(s.events.tear->start, 0.2);
  EXPECT_DOUBLE_EQ(s.events.tear->strain, 0.5);
  EXPECT_EQ(s.events.tear->ticks, 2);
  EXPECT_EQ(s.events.tear->max_per_tick, 8);
}

// Parsing `events` fails with a message containing `fragment`.
void expect_error(const json& events, const std::string& fragment) {
  const std::string message = error_of(events);
  EXPECT_NE(message.find(fragment), std::string::npos) << message;
}

TEST(ScenarioEvents, ErrorsNameTheFileAndPath) {
  expect_error(json::object(), "scene.json: events: expected an array");
  expect_error(json::array({json::parse(R"({"carve": {}})")}), "events[0].carve: unknown field");
  json extra = kCut;
  extra["cut"]["depth"] = 1;
  expect_error(json::array({extra}), "events[0].cut.depth: unknown field");
  json one = kCut;
  one["cut"]["keyframes"].erase(1);
  expect_error(json::array({one}), "events[0].cut.keyframes: expected an array of at least two");
  json unsorted = kCut;
  unsorted["cut"]["keyframes"][1]["t"] = 0.1;
  expect_error(json::array({unsorted}), "events[0].cut.keyframes[1].t: keyframes must be sorted");
  json point = kCut;
  point["cut"]["keyframes"][0]["b"] = point["cut"]["keyframes"][0]["a"];
  expect_error(json::array({point}), "events[0].cut.keyframes[0]: expected a blade of non-zero length");
  expect_error(json::array({kCut, kCut}), "events[1].cut.name: duplicate cut name \"incision\"");
  expect_error(json::array({json::parse(R"({"tear": {"start": 0}})")}), "events[0].tear.strain: missing (required)");
  expect_error(json::array({json::parse(R"({"tear": {"strain": -1}})")}), "events[0].tear.strain: expected a value > 0");
  const json tear = json::parse(R"({"tear": {"strain": 0.5}})");
  expect_error(json::array({tear, tear}), "events[1]: only one \"tear\"");
}

TEST(ScenarioEvents, AppliedAtIsForACutOfTwoKeyframesAndNotBeforeIt) {
  json later = kCut;
  later["cut"]["applied_at"] = 0.5;
  const Scenario s = parse_scenario(with_events(json::array({later})), "/data", "scene.json");
  ASSERT_TRUE(s.events.cuts[0].applied_at);
  EXPECT_EQ(*s.events.cuts[0].applied_at, 0.5);
  EXPECT_FALSE(parse_scenario(with_events(json::array({kCut})), "/data", "scene.json").events.cuts[0].applied_at);
  json early = later;
  early["cut"]["applied_at"] = 0.05;
  expect_error(json::array({early}), "events[0].cut.applied_at: expected a time >= the first keyframe's t");
  json three = later;
  three["cut"]["keyframes"].push_back(json::parse(R"({"t": 0.4, "a": [0, 0, -1], "b": [0, 1, -1]})"));
  expect_error(json::array({three}), "events[0].cut.applied_at: is for a cut over one tick (exactly two keyframes");
}

const json kSuture = json::parse(R"({"suture": {"t": 0.4, "along": "incision", "spacing": 0.005,
    "max_distance": 0.02, "stiffness": 50, "rate": 0.01, "min_length": 0.001}})");

TEST(ScenarioEvents, SuturesAsWritten) {
  const json pairs = json::parse(R"({"suture": {"t": 0.5, "pairs": [[3, 7], [12, 2]], "stiffness": 20, "length": 0.004}})");
  const Scenario s = parse_scenario(with_events(json::array({kSuture, kCut, pairs})), "/data", "scene.json");
  ASSERT_EQ(s.events.sutures.size(), 2u);
  const SutureEvent& a = s.events.sutures[0];
  EXPECT_EQ(a.where, "scene.json: events[0].suture");
  EXPECT_DOUBLE_EQ(a.t, 0.4);
  EXPECT_EQ(a.along, "incision");  // a cut later in the list is fine
  EXPECT_DOUBLE_EQ(a.spacing, 0.005);
  EXPECT_DOUBLE_EQ(a.max_distance, 0.02);
  EXPECT_DOUBLE_EQ(a.stiffness, 50);
  EXPECT_DOUBLE_EQ(a.rate, 0.01);
  EXPECT_DOUBLE_EQ(a.min_length, 0.001);
  EXPECT_FALSE(a.length.has_value());
  EXPECT_DOUBLE_EQ(a.tied_length(0.03), 0.03);  // the current distance by default
  const SutureEvent& b = s.events.sutures[1];
  EXPECT_EQ(b.pairs, (std::vector<std::array<int32_t, 2>>{{3, 7}, {12, 2}}));
  EXPECT_TRUE(b.along.empty());
  EXPECT_DOUBLE_EQ(b.rate, 0);  // no tightening unless asked
  EXPECT_DOUBLE_EQ(b.tied_length(0.03), 0.004);
  EXPECT_TRUE(s.events.any());
}

TEST(ScenarioEvents, SutureErrorsNameTheField) {
  auto with = [](const char* key, const json& value) {
    json j = kSuture;
    if (value.is_null())
      j["suture"].erase(key);
    else
      j["suture"][key] = value;
    return json::array({kCut, j});
  };
  expect_error(with("stiffness", 0), "events[1].suture.stiffness: expected a value > 0");
  expect_error(with("stiffness", nullptr), "events[1].suture.stiffness: missing (required)");
  expect_error(with("t", nullptr), "events[1].suture.t: missing (required)");
  expect_error(with("rate", -1), "events[1].suture.rate: expected a value >= 0");
  expect_error(with("min_length", -0.1), "events[1].suture.min_length: expected a value >= 0");
  expect_error(with("length", -0.1), "events[1].suture.length: expected a value >= 0");
  expect_error(with("spacing", nullptr), "events[1].suture.spacing: missing (required)");
  expect_error(with("max_distance", 0), "events[1].suture.max_distance: expected a value > 0");
  expect_error(with("knot", "square"), "events[1].suture.knot: unknown field");
  expect_error(with("along", "other"), "events[1].suture.along: no cut named \"other\" (cuts: \"incision\")");
  expect_error(json::array({kSuture}), "events[0].suture.along: no cut named \"incision\" (cuts: none)");
  expect_error(with("t", 0.2), "events[1].suture.along: the cut \"incision\" ends at t = 0.3");
  expect_error(with("pairs", json::parse("[[1, 2]]")), "events[1].suture: expected exactly one of \"pairs\"");
  const auto pairs = [](const json& p) {
    return json::array({json{{"suture", {{"t", 0}, {"stiffness", 1}, {"pairs", p}}}}});
  };
  expect_error(pairs(json::array()), "events[0].suture.pairs: expected a non-empty array");
  expect_error(pairs(json::parse("[[1, 2, 3]]")), "events[0].suture.pairs[0]: expected a pair of point ids");
  expect_error(pairs(json::parse("[[1, -2]]")), "events[0].suture.pairs[0][1]: expected a point id >= 0");
  expect_error(pairs(json::parse("[[4, 4]]")), "events[0].suture.pairs[0]: a suture joins two different points");
  json spaced = pairs(json::parse("[[1, 2]]"));
  spaced[0]["suture"]["spacing"] = 0.01;
  expect_error(spaced, "events[0].suture.spacing: only with \"along\"");
}

}  // namespace
}  // namespace scenario_events_test
}  // namespace organsim
