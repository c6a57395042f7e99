// The scenario's `events` section: values as documented, strict errors that
// name the JSON path, and blade interpolation.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/scenario/scenario.h"
#include "core/util/error.h"

namespace organsim {
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

}  // namespace
}  // namespace organsim
