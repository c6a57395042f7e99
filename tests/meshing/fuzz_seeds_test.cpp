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
#include "tests/fuzz/fuzz_inputs.h"

namespace organsim {
namespace {

namespace fs = std::filesystem;

const fs::path kRoot = ORGANSIM_SOURCE_DIR;

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

struct Row {
  std::string name, kind, ext;
  std::vector<std::string> globs;
};

std::vector<Row> harness_rows() {
  std::ifstream in(kRoot / "tests" / "fuzz" / "harnesses.txt");
  std::vector<Row> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    Row r;
    fields >> r.name >> r.kind >> r.ext;
    for (std::string glob; fields >> glob;) r.globs.push_back(glob);
    rows.push_back(r);
  }
  return rows;
}

// The files a glob "folder/prefix*suffix" (one '*', in the file name) names, relative to the root.
std::vector<fs::path> expand(const std::string& glob) {
  const fs::path pattern(glob);
  const std::string name = pattern.filename().string();
  const size_t star = name.find('*');
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(kRoot / pattern.parent_path())) {
    const std::string f = e.path().filename().string();
    const bool match = star == std::string::npos
                           ? f == name
                           : f.size() >= name.size() - 1 && f.compare(0, star, name, 0, star) == 0 &&
                                 f.compare(f.size() - (name.size() - star - 1), std::string::npos, name, star + 1) == 0;
    if (e.is_regular_file() && match) files.push_back(fs::relative(e.path(), kRoot));
  }
  return files;
}

// What the row's harness runs on `text`, read as `source`; for an accepted
// input, how many faces, tets, scenario ticks, sweep cases or voxels it gave (a reader that read
// nothing from a good file accepts it empty).
size_t run_harness(const Row& row, const std::string& text, const std::string& source) {
  if (row.kind == "surface") return fuzz::surface_input(text, source).faces.size();
  if (row.kind == "tet") return fuzz::tet_input(text, source).tets.size();
  if (row.kind == "surface_check") return fuzz::surface_check_input(text, source).faces.size();
  if (row.kind == "scenario") {
    const Scenario s = fuzz::scenario_input(text, source);
    fuzz::scenario_model(s);
    return static_cast<size_t>(s.time.ticks());
  }
  if (row.kind == "sweep") return fuzz::sweep_input(text, source).cases.size();
  if (row.kind == "study") return fuzz::study_input(text, source);
  if (row.kind == "igtl") return fuzz::igtl_input(text).size();
  if (row.kind == "measured_curve") return fuzz::measured_curve_input(text, source);
  if (row.kind == "client_transform") return fuzz::client_transform_input(text, source);
  if (row.kind == "sweep_files") return fuzz::sweep_files_input(text, source);
  if (row.kind == "label_image") return static_cast<size_t>(fuzz::label_image_input(text, source).voxel_count());
  ADD_FAILURE() << "harnesses.txt: row " << row.name << " has an unknown kind " << row.kind;
  return 0;
}

TEST(FuzzSeeds, EverySeedIsAcceptedUnlessListedAsRefused) {
  const std::vector<Row> rows = harness_rows();
  ASSERT_GE(rows.size(), 14u);
  size_t accepted = 0, refused = 0;
  for (const Row& row : rows) {
    std::vector<fs::path> seeds;
    for (const auto& e : fs::directory_iterator(kRoot / "tests" / "fuzz" / "corpus" / row.name))
      seeds.push_back(fs::relative(e.path(), kRoot));
    for (const std::string& glob : row.globs) {
      const std::vector<fs::path> files = expand(glob);
      EXPECT_FALSE(files.empty()) << row.name << ": seed glob " << glob << " names no file";
      seeds.insert(seeds.end(), files.begin(), files.end());
    }
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
}  // namespace organsim
