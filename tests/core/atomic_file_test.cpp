// write_file_atomically on its real failure paths: a write the operating
// system refuses midway and a rename that fails. Either way nothing appears
// under the final name, no temporary is left, and an earlier file survives.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "file_size_limit.h"

namespace organsim {
namespace atomic_file_test {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(AtomicFile, AWriteThatFailsMidwayLeavesNothingAndKeepsTheOldFile) {
  const fs::path dir = fresh_dir("atomic_write_fails");
  const fs::path path = dir / "out.txt";
  write_file_atomically(path, [](std::ostream& out) { out << "complete earlier file\n"; });
  const std::string big(1 << 20, 'x');  // 1 MiB against a 64 KiB limit
  try {
    testing::FileSizeLimit limit(64 * 1024);
    write_file_atomically(path, [&](std::ostream& out) { out << big; });
    ADD_FAILURE() << "a write beyond the file size limit did not fail";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Output);
    EXPECT_NE(std::string(e.what()).find(path.string() + ": write failed"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_text_file(path), "complete earlier file\n");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"out.txt"});  // no temporary left behind
}

TEST(AtomicFile, ARenameThatFailsLeavesNoTemporary) {
  const fs::path dir = fresh_dir("atomic_rename_fails");
  // The final name is a non-empty folder: the file cannot replace it.
  const fs::path path = dir / "taken";
  fs::create_directories(path / "inside");
  try {
    write_file_atomically(path, [](std::ostream& out) { out << "data\n"; });
    ADD_FAILURE() << "renaming onto a non-empty folder did not fail";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Output);
    EXPECT_NE(std::string(e.what()).find(path.string() + ": cannot rename from "), std::string::npos) << e.what();
  }
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"taken"});
  EXPECT_TRUE(fs::is_directory(path / "inside"));
}

}  // namespace
}  // namespace atomic_file_test
}  // namespace organsim
