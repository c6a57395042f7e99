#pragma once
// The fuzz harness table (tests/fuzz/harnesses.txt) read for tests: its
// rows, each row's seed files (the hand-made corpus and the row's globs) and
// what the row's harness runs on an input (tests/fuzz/fuzz_inputs.h). The
// seed test and the truncation test both go through it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_inputs.h"

namespace organsim::fuzz_rows {

namespace fs = std::filesystem;

inline const fs::path kRoot = ORGANSIM_SOURCE_DIR;

struct Row {
  std::string name, kind, ext;
  std::vector<std::string> globs;
};

inline std::vector<Row> harness_rows() {
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
inline std::vector<fs::path> expand(const std::string& glob) {
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

// The row's seeds, relative to the repository: its corpus folder's files,
// then each glob's (a glob naming no file is a test failure).
inline std::vector<fs::path> row_seeds(const Row& row) {
  std::vector<fs::path> seeds;
  for (const auto& e : fs::directory_iterator(kRoot / "tests" / "fuzz" / "corpus" / row.name))
    seeds.push_back(fs::relative(e.path(), kRoot));
  for (const std::string& glob : row.globs) {
    const std::vector<fs::path> files = expand(glob);
    EXPECT_FALSE(files.empty()) << row.name << ": seed glob " << glob << " names no file";
    seeds.insert(seeds.end(), files.begin(), files.end());
  }
  return seeds;
}

// What the row's harness runs on `text`, read as `source`; for an accepted
// input, how many faces, tets, scenario ticks, sweep cases or voxels it gave (a reader that read
// nothing from a good file accepts it empty).
inline size_t run_harness(const Row& row, const std::string& text, const std::string& source) {
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

}  // namespace organsim::fuzz_rows
