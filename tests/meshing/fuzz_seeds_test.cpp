// Every seed of the fuzz corpus (tests/fuzz/harnesses.txt: the hand-made
// files in tests/fuzz/corpus/<harness>/ and the row's seed globs) goes
// through what its harness runs (tests/fuzz/fuzz_inputs.h), read as the
// harness reads it. The harnesses accept any clean error (and any empty
// result), so a reader that started refusing good files, or reading nothing
// from them, would go unnoticed there: here every seed must be accepted and
// not empty, except the few listed below that exist to be refused, which
// must get their error. In tests/meshing because the surface_check harness
// runs the CGAL checks.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/util/atomic_file.h"
#include "tests/meshing/fuzz_rows.h"

namespace organsim {
namespace fuzz_seeds_test {
namespace {

using namespace fuzz_rows;

// Seeds that exist to be refused (the fuzzer starts next to a refusal, the
// stress scenarios test it), relative to the repository, and what the error
// each gets says.
const std::map<std::string, std::string> kRefused = {
    {"tests/fuzz/corpus/off/quads.off", "fuzz.off: line 11: face 0 has 4 vertices; not a triangle mesh"},
    {"tests/fuzz/corpus/obj/quad.obj", "fuzz.obj: line 9: face 0 has 4 vertices; not a triangle mesh"},
    {"scenarios/stress/inverted.mesh", "fuzz.mesh: tetrahedron 17 is inverted"},
    {"tests/fuzz/corpus/scenario/extreme_volume_modulus.json", "exceeds the critical step dt_crit = 1.519e-64 s"},
    {"scenarios/stress/zero_density.json", "fuzz.json: material.density: expected a value > 0 (got 0)"},
    {"scenarios/stress/negative_density.json", "fuzz.json: material.density: expected a value > 0 (got -1000)"},
    {"scenarios/stress/stiff_x1000.json", "exceeds the critical step dt_crit = 0.0001416 s"},
    {"tests/fuzz/corpus/surface_check/open.off", "fuzz.off: open surface: 3 border edges"},
    {"tests/fuzz/corpus/sweep/bad_entries.json", "index out of range (the base scenario's array has 2 elements)"},
    {"tests/fuzz/corpus/study/unsorted_ticks.json", "fuzz.json: ticks[1]: expected a tick index above the one before"},
};

TEST(FuzzSeeds, EverySeedIsAcceptedUnlessListedAsRefused) {
  const std::vector<Row> rows = harness_rows();
  ASSERT_GE(rows.size(), 14u);
  size_t accepted = 0, refused = 0;
  for (const Row& row : rows) {
    const std::vector<fs::path> seeds = row_seeds(row);
    EXPECT_FALSE(seeds.empty()) << row.name << " has no seed";
    for (const fs::path& seed : seeds) {
      SCOPED_TRACE(row.name + ": " + seed.string());
      const std::string source = "fuzz" + row.ext;  // as the harness names its input
      const auto listed = kRefused.find(seed.string());
      try {
        EXPECT_GT(run_harness(row, read_text_file(kRoot / seed), source), 0u) << "accepted, but empty";
        EXPECT_EQ(listed, kRefused.end()) << "accepted, but listed as refused";
        ++accepted;
      } catch (const Error& e) {
        EXPECT_NE(listed, kRefused.end()) << "refused: " << e.what();
        if (listed != kRefused.end()) {
          EXPECT_NE(std::string(e.what()).find(listed->second), std::string::npos) << e.what();
        }
        ++refused;
      }
    }
  }
  EXPECT_EQ(refused, kRefused.size());
  std::cout << accepted << " seeds accepted, " << refused << " refused as listed\n";
}

}  // namespace
}  // namespace fuzz_seeds_test
}  // namespace organsim
