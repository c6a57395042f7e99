// The progress line of `organsim run` and `organsim mesh`: on stderr when it
// is a terminal (run under a pseudo-terminal with util-linux `script`), and
// nothing extra when stderr is a file or a pipe.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/mesh/example_shapes.h"
#include "core/mesh/mesh_io.h"
#include "run_cli_test_util.h"
#include "tests/core/mesh_io_test_util.h"

namespace organsim {
namespace progress_line_test {
namespace {

namespace fs = std::filesystem;


// Runs `organsim ARGS` on a pseudo-terminal: stdout and stderr both go to
// the terminal, whose transcript is returned.
test::CliResult run_on_terminal(const std::string& args, const fs::path& dir) {
  const fs::path transcript = dir / "terminal.txt";
  const std::string cmd = "script -qec \"'" + std::string(ORGANSIM_EXE) + "' " + args + "\" /dev/null >'" +
                          transcript.string() + "' 2>&1 </dev/null";
  const int status = std::system(cmd.c_str());
  test::CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = test::slurp(transcript);
  return r;
}

// A 0.3 s push on the small stress box: a few hundred ticks, quick.
fs::path short_scenario(const fs::path& dir) {
  const fs::path stress = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "stress";
  nlohmann::json j = nlohmann::json::parse(std::ifstream(stress / "gentle_push.json"));
  j["mesh"]["tet"] = (stress / "box.mesh").string();
  j["time"]["duration"] = 0.3;
  std::ofstream(dir / "short.json") << j.dump();
  return dir / "short.json";
}

TEST(ProgressLine, RunShowsTicksRealTimeFactorAndTimeLeftOnATerminal) {
  const fs::path dir = testing::fresh_test_dir("app");
  const test::CliResult r = run_on_terminal("run " + short_scenario(dir).string() + " -o " + (dir / "out").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("\rorgansim run: tick 300/300 (100 %), real-time factor "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" s left"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("done:"), std::string::npos) << r.out;  // the usual report still follows
}

TEST(ProgressLine, RunPrintsNothingExtraWhenStderrIsNotATerminal) {
  const fs::path dir = testing::fresh_test_dir("app");
  const test::CliResult r = test::run_organsim("run " + short_scenario(dir).string() + " -o " + (dir / "out").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("tick"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find('\r'), std::string::npos) << r.out;
}

TEST(ProgressLine, MeshShowsItsStageOnATerminalOnly) {
  const fs::path dir = testing::fresh_test_dir("app");
  write_surface(dir / "sphere.off", make_sphere_surface(0.05, 2));
  const std::string args = "mesh " + (dir / "sphere.off").string() + " -o " + (dir / "out.mesh").string() +
                           " --target-points 300 --no-exude";
  const test::CliResult tty = run_on_terminal(args, dir);
  ASSERT_EQ(tty.exit_code, 0) << tty.out;
  EXPECT_NE(tty.out.find("\rorgansim mesh: checking the surface"), std::string::npos) << tty.out;
  EXPECT_NE(tty.out.find("\rorgansim mesh: searching the cell size for 300 points: try 1 of at most 10"),
            std::string::npos)
      << tty.out;
  EXPECT_NE(tty.out.find("\rorgansim mesh: writing "), std::string::npos) << tty.out;

  const test::CliResult file = test::run_organsim(args, dir);
  ASSERT_EQ(file.exit_code, 0) << file.err;
  EXPECT_EQ(file.err, "");
  EXPECT_EQ(file.out.find("organsim mesh:"), std::string::npos) << file.out;
}

}  // namespace
}  // namespace progress_line_test
}  // namespace organsim
