// The force log: documented fields, one sample per tick, atomic writing.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "core/io/force_log.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "file_size_limit.h"

namespace organsim {
namespace run_force_log_test {
namespace {

namespace fs = std::filesystem;

ForceLogMeta sample_meta() {
  ForceLogMeta m;
  m.scenario = "scenarios/x.json";
  m.backend = "cpu";
  m.device = "test CPU";
  m.precision = "double";
  m.points = 10;
  m.springs = 30;
  m.tets = 8;
  m.dt = 1e-4;
  m.substeps = 10;
  m.duration = 0.003;
  m.completed = true;
  m.extra["dt_crit"] = 2e-3;
  return m;
}

ForceSamples three_samples() {
  ForceSamples s;
  for (int i = 0; i < 3; ++i) {
    s.push(0.001 * (i + 1), Vec3(i, 0, -i), Vec3(0, i, 0), Vec3(0, 0, 0.1 - 0.01 * i), i);
  }
  return s;
}

TEST(ForceLog, JsonHasTheDocumentedFieldsAndOneSamplePerTick) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "force_log_fields";
  fs::remove_all(dir);
  write_force_log(dir / "forces.json", sample_meta(), three_samples());
  const auto j = nlohmann::json::parse(read_text_file(dir / "forces.json"));

  const auto& meta = j.at("meta");
  for (const char* key : {"organsim_version", "scenario", "backend", "device", "precision",
                          "reaction_latency_ticks", "points", "springs", "tets", "dt", "substeps",
                          "duration", "wall_seconds", "steps_per_second", "real_time_factor", "completed",
                          "stop_reason"}) {
    EXPECT_TRUE(meta.contains(key)) << key;
  }
  EXPECT_EQ(meta.at("organsim_version"), ORGANSIM_VERSION);
  EXPECT_EQ(meta.at("springs"), 30);
  EXPECT_EQ(meta.at("completed"), true);
  EXPECT_DOUBLE_EQ(meta.at("tick").get<double>(), 1e-3);  // dt * substeps
  EXPECT_DOUBLE_EQ(meta.at("dt_crit").get<double>(), 2e-3);  // extras are merged into meta

  const auto& s = j.at("samples");
  for (const char* col : {"t", "force", "torque", "tool_position", "contacts"}) {
    ASSERT_TRUE(s.contains(col)) << col;
    EXPECT_EQ(s.at(col).size(), 3u) << col;
  }
  EXPECT_EQ(s.at("force")[2].size(), 3u);  // [x, y, z]
  // Values round-trip exactly (nlohmann writes doubles with 17 digits).
  EXPECT_EQ(s.at("t")[1].get<double>(), 0.002);
  EXPECT_EQ(s.at("force")[2][2].get<double>(), -2.0);
  EXPECT_EQ(s.at("tool_position")[2][2].get<double>(), 0.1 - 0.02);
  EXPECT_EQ(s.at("contacts")[2], 2);
}

TEST(ForceLog, NoFileUnderTheFinalNameWhenWritingFails) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "force_log_atomic";
  fs::remove_all(dir);
  fs::create_directories(dir);
  // A log of 20,000 ticks is ~2 MB of JSON; the operating system refuses
  // the write after 16 KiB, midway through the samples.
  ForceSamples many;
  for (int i = 0; i < 20000; ++i) many.push(1e-3 * i, Vec3(i, 0, -i), Vec3(0, i, 0), Vec3(0, 0, 0.1), i);
  const auto write_limited = [&] {
    testing::FileSizeLimit limit(16 * 1024);
    write_force_log(dir / "forces.json", sample_meta(), many);
  };
  EXPECT_THROW(write_limited(), Error);
  EXPECT_FALSE(fs::exists(dir / "forces.json"));
  EXPECT_TRUE(fs::is_empty(dir)) << "a temporary was left behind";

  // An earlier complete log is not clobbered by a failed rewrite.
  write_force_log(dir / "forces.json", sample_meta(), three_samples());
  const std::string before = read_text_file(dir / "forces.json");
  EXPECT_THROW(write_limited(), Error);
  EXPECT_EQ(read_text_file(dir / "forces.json"), before);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(ForceLog, IncompleteRunSaysSoAndStaysValidJson) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "force_log_incomplete";
  ForceLogMeta meta = sample_meta();
  meta.completed = false;
  meta.stop_reason = "t = 0.002 s: point 7 non-finite";
  ForceSamples s = three_samples();
  s.force[1] = Vec3(std::nan(""), 0, 0);  // JSON has no NaN: written as null, file stays parseable
  write_force_log(dir / "forces.json", meta, s);
  const auto j = nlohmann::json::parse(read_text_file(dir / "forces.json"));
  EXPECT_EQ(j["meta"]["completed"], false);
  EXPECT_EQ(j["meta"]["stop_reason"], "t = 0.002 s: point 7 non-finite");
  EXPECT_TRUE(j["samples"]["force"][1][0].is_null());
}

}  // namespace
}  // namespace run_force_log_test
}  // namespace organsim
