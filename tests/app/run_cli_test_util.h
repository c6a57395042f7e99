#pragma once
// Running the organsim executable from tests: exit code, stdout and stderr.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace organsim::test {

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs `organsim ARGS` with stdout/stderr captured in files under `dir`.
inline CliResult run_organsim(const std::string& args, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  const auto out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string cmd = std::string("'") + ORGANSIM_EXE + "' " + args + " >'" + out.string() + "' 2>'" +
                          err.string() + "'";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

// Exit 6 (ErrorKind::Backend) is acceptable from a GL run only when this
// machine cannot create an OpenGL 4.5 context at all: that error comes from
// EGL context creation and starts "EGL: ". A backend that got its context and
// then failed (a shader that no longer compiles, a buffer it could not make)
// is a bug, and this fails the test.
inline void expect_no_gl_context_here(const CliResult& r) {
  EXPECT_EQ(r.exit_code, 6) << r.err;
  EXPECT_EQ(r.err.rfind("organsim: error: EGL: ", 0), 0u)
      << "the GL backend failed with a context available (not a missing-GL machine):\n" << r.err;
}

}  // namespace organsim::test
