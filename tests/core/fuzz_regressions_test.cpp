// Every input the fuzzer found that crashed, hung or tripped a sanitizer
// (tests/fuzz/regressions/<harness>/) now gets the clean error listed here,
// naming the file. The fuzz seeds include these files, so the fuzzer keeps
// mutating around them too.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "core/mesh/mesh_io.h"
#include "core/scenario/scenario.h"
#include "core/stability/critical_step.h"
#include "core/sweep/sweep_results.h"
#include "core/util/atomic_file.h"
#include "mesh_io_test_util.h"

namespace organsim {
namespace fuzz_regressions_test {
namespace {

namespace fs = std::filesystem;

const fs::path kRegressions = fs::path(ORGANSIM_SOURCE_DIR) / "tests" / "fuzz" / "regressions";

struct Regression {
  const char* file;      // under tests/fuzz/regressions/
  const char* expected;  // in the message, after "<file>: "
};

// One row per saved input; how each was found is in docs/robustness.md.
const Regression kCases[] = {
    {"ply_ascii/end_header_at_eof.ply", "PLY element 'vertex' lacks an x, y or z property"},
    {"ply_binary/end_header_at_eof.ply", "PLY element 'vertex' lacks an x, y or z property"},
    {"ply_binary/float_list_length.ply", "fake 0: list length 2.406e-38, expected a count >= 0"},
    {"vtk/huge_point_count.vtk", "line 5: 5750106523498388593 points cannot fit in the rest of the file"},
    // A UInt64 byte-count header of 2^64 - 1: the message used to cast it
    // back from a double past the uint64 range (UBSan).
    {"vtu/huge_byte_count.vtu", "<Cells> DataArray \"offsets\": header declares 1.845e+19 bytes, only 171 present"},
    {"scenario/number_overflow.json", "invalid JSON: number overflow parsing '4223372036854E7580' (too large for a number)"},
    // A force of two values: --collect read past the JSON array (ASan).
    {"sweep_files/two_value_force.json", "samples.force[0]: expected three numbers or nulls (N)"},
};

// Reads the input the way its harness does (the harness's folder, then the
// extension, picks the reader).
void parse(const std::string& harness, const std::string& bytes, const std::string& source) {
  if (harness == "sweep_files") {
    force_log_summary(bytes, source, {});
  } else if (is_surface_path(source)) {
    parse_surface(bytes, source);
  } else if (is_tet_mesh_path(source)) {
    parse_tet_mesh(bytes, source);
  } else {
    parse_scenario_text(bytes, "/fuzz", source);
  }
}

TEST(FuzzRegressions, EachSavedInputGetsItsCleanError) {
  for (const Regression& r : kCases) {
    const fs::path path = kRegressions / r.file;
    const std::string source = path.filename().string();
    const std::string harness = path.parent_path().filename().string();
    const std::string msg = testing::error_message([&] { parse(harness, read_text_file(path), source); });
    EXPECT_EQ(msg.rfind(source + ": ", 0), 0u) << r.file << ": " << msg;
    EXPECT_NE(msg.find(r.expected), std::string::npos) << r.file << ": " << msg;
  }
}

TEST(FuzzRegressions, EverySavedInputIsListed) {
  std::set<std::string> listed;
  for (const Regression& r : kCases) listed.insert(r.file);
  for (const auto& e : fs::recursive_directory_iterator(kRegressions)) {
    // surface_check and the image readers need the meshing library: tests/meshing checks theirs.
    const std::string harness = e.path().parent_path().filename().string();
    if (!e.is_regular_file() || harness == "surface_check" || harness == "nifti" ||
        harness == "inr")
      continue;
    const std::string rel = fs::relative(e.path(), kRegressions).string();
    EXPECT_TRUE(listed.count(rel)) << rel << " has no row in kCases";
  }
}

// The scenario harness's input tests/fuzz/corpus/scenario/extreme_volume_modulus.json
// (volume_modulus 4.4e13) made the suggested substep count 7e60, cast to an
// int: undefined behaviour. It is clamped to the int range now.
TEST(FuzzRegressions, AStepSuggestionForAnExtremeStiffnessStaysInRange) {
  StabilityReport report;
  report.dt_crit = 1e-70;  // s
  const StepSuggestion s = suggest_step(report, 1e-3, 0.9);
  EXPECT_EQ(s.substeps, 2147483647);
  EXPECT_GT(s.dt, 0.0);
}

}  // namespace
}  // namespace fuzz_regressions_test
}  // namespace organsim
