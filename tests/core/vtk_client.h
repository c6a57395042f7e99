#pragma once
// VTK itself as the judge of the VTK files we write and the source of files
// we read: runs a Python script with Debian's python3-vtk9 (scripts/setup.sh
// installs it). /usr/bin/python3 explicitly: a python3 earlier on PATH may
// not see Debian's packages.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace organsim::testing {

// Runs `script` in `dir` (as its working folder) and returns its stdout;
// a failing script fails the test with its stderr.
inline std::string run_vtk_python(const std::string& script, const std::filesystem::path& dir) {
  const auto script_path = dir / "client.py", out = dir / "client.out", err = dir / "client.err";
  std::ofstream(script_path) << "import vtk\n" << script;
  const std::string cmd = "cd '" + dir.string() + "' && /usr/bin/python3 '" + script_path.string() + "' >'" +
                          out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  const auto slurp = [](const std::filesystem::path& p) {
    std::stringstream s;
    s << std::ifstream(p).rdbuf();
    return s.str();
  };
  const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  EXPECT_TRUE(ok) << "VTK client failed (is python3-vtk9 installed? bash scripts/setup.sh):\n" << slurp(err);
  return ok ? slurp(out) : std::string();
}

}  // namespace organsim::testing
