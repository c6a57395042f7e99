#pragma once
// Helpers for the mesh reader tests: a fresh temporary folder per test and
// small fixture files written by the tests themselves.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/mesh/mesh_io_detail.h"
#include "core/mesh/tet_mesh.h"
#include "core/util/error.h"

namespace organsim::testing {

inline std::filesystem::path fresh_test_dir(const std::string& group) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      std::filesystem::path(ORGANSIM_TEST_TMP) / group / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::filesystem::path write_fixture(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  return path;
}

// A tet mesh written by the format writers directly, past write_tet_mesh's
// refusal of non-positive tets: fixtures of bad meshes for the readers.
inline std::filesystem::path write_bad_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh) {
  std::ofstream out(path, std::ios::binary);
  if (path.extension() == ".vtk") mesh_io::write_vtk(out, mesh);
  else mesh_io::write_medit(out, mesh);
  return path;
}

// Runs f, which must throw organsim::Error; returns its message ("" if it did not throw).
template <class F>
std::string error_message(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an organsim::Error";
  return "";
}

// A unit cube split into 5 positively oriented tets: one regular tet on the
// even corners (0, 3, 5, 6 with id = x + 2y + 4z) and four corner tets.
inline TetMesh five_tet_cube() {
  TetMesh mesh;
  for (int v = 0; v < 8; ++v) mesh.points.emplace_back(v & 1, (v >> 1) & 1, (v >> 2) & 1);
  mesh.tets = {{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 3, 6}, {4, 0, 5, 6}, {7, 3, 5, 6}};
  for (Tet& t : mesh.tets) {
    if (signed_volume(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]) < 0) std::swap(t[2], t[3]);
  }
  return mesh;
}

}  // namespace organsim::testing
