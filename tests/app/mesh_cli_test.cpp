// `organsim mesh` end to end: bad input exits non-zero with a one-line error
// naming the file and the problem, and writes no output file; --json parses.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include "../core/mesh_io_test_util.h"
#include "core/mesh/example_shapes.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "core/util/atomic_file.h"

namespace organsim {
namespace mesh_cli_test {
namespace {

using testing::five_tet_cube;
using testing::fresh_test_dir;
using testing::write_fixture;

struct CliRun {
  int exit_code;
  std::string out;  // stdout
  std::string err;  // stderr
};

CliRun run_organsim(const std::string& args, const std::filesystem::path& dir) {
  const std::string err_path = (dir / "stderr.txt").string();
  const std::string command = std::string(ORGANSIM_EXE) + " " + args + " 2>" + err_path;
  FILE* pipe = popen(command.c_str(), "r");
  EXPECT_NE(pipe, nullptr);
  std::string out;
  std::array<char, 4096> buffer{};
  while (size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) out.append(buffer.data(), n);
  const int status = pclose(pipe);
  std::ifstream err_file(err_path);
  std::string err((std::istreambuf_iterator<char>(err_file)), std::istreambuf_iterator<char>());
  std::filesystem::remove(err_path);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out, err};
}

// Files in `dir` other than `keep` (to catch outputs and stray temporaries).
std::vector<std::string> other_files(const std::filesystem::path& dir, const std::string& keep) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().filename() != keep) names.push_back(entry.path().filename().string());
  }
  return names;
}

struct BadCase {
  const char* name;      // input file name
  std::string content;   // written unless empty
  const char* expected;  // in the error message
};

std::string off_text(const TriangleMesh& m) {
  std::string s = "OFF\n" + std::to_string(m.points.size()) + " " + std::to_string(m.faces.size()) + " 0\n";
  for (const Vec3& p : m.points) s += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  for (const Tri& f : m.faces) s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
  return s;
}

std::string vtk_text(const TetMesh& m) {
  std::string s = "# vtk DataFile Version 3.0\nfixture\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS " +
                  std::to_string(m.points.size()) + " double\n";
  for (const Vec3& p : m.points) s += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  s += "CELLS " + std::to_string(m.tets.size()) + " " + std::to_string(5 * m.tets.size()) + "\n";
  for (const Tet& t : m.tets) {
    s += "4 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + " " + std::to_string(t[3]) + "\n";
  }
  s += "CELL_TYPES " + std::to_string(m.tets.size()) + "\n";
  for (size_t i = 0; i < m.tets.size(); ++i) s += "10\n";
  return s;
}

std::vector<BadCase> bad_cases() {
  TriangleMesh open = make_sphere_surface(0.05, 2);
  open.faces.pop_back();
  TriangleMesh overlapping = make_sphere_surface(0.05, 2);
  TriangleMesh nested = make_sphere_surface(0.05, 2);
  const TriangleMesh other = make_sphere_surface(0.05, 2);
  const auto n = static_cast<int32_t>(overlapping.points.size());
  for (const Vec3& p : other.points) {
    overlapping.points.push_back(p + Vec3(0.075, 0, 0));  // overlaps the first sphere
    nested.points.push_back(0.5 * p);                     // inside it, same orientation
  }
  for (const Tri& f : other.faces) {
    overlapping.faces.push_back({f[0] + n, f[1] + n, f[2] + n});
    nested.faces.push_back({f[0] + n, f[1] + n, f[2] + n});
  }
  TetMesh inverted = five_tet_cube();
  std::swap(inverted.tets[2][0], inverted.tets[2][1]);
  TetMesh flat = five_tet_cube();
  flat.tets[1] = {0, 1, 3, 2};
  TetMesh range = five_tet_cube();
  range.tets[4][3] = 8;
  // The closed tetrahedron of issue 10 with one coordinate or the scale changed:
  // before the range checks these crashed (SIGFPE), hung, or wrote zero-volume tets.
  const auto tet = [](const std::string& a, const std::string& b) {
    return "OFF\n4 4 0\n0 0 0\n" + a + " 0 0\n0 " + b + " 0\n0 0 " + b + "\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  };
  const TriangleMesh millimetres = make_box_surface({-50, -50, -50}, {50, 50, 50});  // a 10 cm cube written in mm
  return {
      {"huge.off", tet("1e300", "0.1"), "huge.off: the surface is 1e+300 m across (bounding-box diagonal); expected an organ between 0.0001 m and 10 m"},
      {"far.off", tet("1e200", "1e200"), "far.off: the surface is 1.732e+200 m across"},
      {"tiny.off", tet("1e-300", "1e-300"), "tiny.off: the surface is 1.732e-300 m across"},
      {"denormal.off", tet("0.1", "1e-310"), "denormal.off: vertex 2 (0 9.9999999999999694e-311 0) has a denormal coordinate"},
      {"mm.off", off_text(millimetres), "mm.off: the surface is 173.2 m across (bounding-box diagonal); expected an organ between 0.0001 m and 10 m, in metres; if the file is in millimetres, scale it by 0.001 (organsim mesh --scale 0.001"},
      {"coplanar.off", "OFF\n3 2 0\n0 0 0\n0.1 0 0\n0 0.1 0\n3 0 1 2\n3 0 2 1\n", "coplanar.off: all points lie in one plane"},
      {"duplicate.off", "OFF\n5 4 0\n0 0 0\n0.1 0 0\n0 0.1 0\n0 0 0.1\n0.1 0 0\n3 0 2 1\n3 0 4 3\n3 0 3 2\n3 1 2 3\n",
       "duplicate.off: vertex 1 (0.10000000000000001 0 0) and vertex 4 are at the same position"},
      {"missing.off", "", "missing.off: no such file"},
      {"surface.xyz", "1 2 3\n", "surface.xyz: unknown extension '.xyz'"},
      {"nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "nofaces.off: no faces"},
      {"quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n", "quad.off: line 7: face 0 has 4 vertices; not a triangle mesh"},
      {"open.off", off_text(open), "open.off: open surface: 3 border edges"},
      {"overlap.off", off_text(overlapping), "overlap.off: self-intersecting: "},
      {"nested.off", off_text(nested), "nested.off: does not bound a volume"},
      {"inverted.vtk", vtk_text(inverted), "inverted.vtk: tetrahedron 2 is inverted"},
      {"flat.vtk", vtk_text(flat), "flat.vtk: tetrahedron 1 has zero volume"},
      {"range.vtk", vtk_text(range), "tetrahedron 4 (cell 4) has vertex index 8"},
  };
}

TEST(MeshCli, BadInputExitsNonZeroWithOneLineErrorAndWritesNothing) {
  for (const BadCase& c : bad_cases()) {
    const auto dir = fresh_test_dir("mesh_cli") / std::filesystem::path(c.name).stem();
    std::filesystem::create_directories(dir);
    if (!c.content.empty()) write_fixture(dir / c.name, c.content);
    const CliRun run = run_organsim("mesh " + (dir / c.name).string() + " -o " + (dir / "out.mesh").string() +
                                     " --cell-size 0.01", dir);
    EXPECT_EQ(run.exit_code, 3) << c.name << ": " << run.err;  // ErrorKind::Input
    EXPECT_NE(run.err.find(c.expected), std::string::npos) << c.name << ": " << run.err;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << c.name << ": " << run.err;
    EXPECT_TRUE(other_files(dir, c.name).empty()) << c.name << ": an output or temporary file was left";
  }
}

TEST(MeshCli, InwardSurfaceIsFixedAndSaysSo) {
  const auto dir = fresh_test_dir("mesh_cli");
  TriangleMesh inward = make_sphere_surface(0.05, 2);
  for (Tri& f : inward.faces) std::swap(f[1], f[2]);
  write_surface(dir / "inward.off", inward);
  const CliRun run = run_organsim("mesh " + (dir / "inward.off").string() + " -o " + (dir / "out.vtk").string() +
                                   " --cell-size 0.015 --no-exude", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("was oriented inward: its faces were reversed"), std::string::npos) << run.out;
  EXPECT_GT(read_tet_mesh(dir / "out.vtk").tets.size(), 0u);
}

TEST(MeshCli, JsonReportParsesAndMatchesTheWrittenMesh) {
  const auto dir = fresh_test_dir("mesh_cli");
  write_surface(dir / "sphere.off", make_sphere_surface(0.05, 3));
  const CliRun run = run_organsim("mesh " + (dir / "sphere.off").string() + " -o " + (dir / "sphere.mesh").string() +
                                   " --cell-size 0.012 --json", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  const TetMesh mesh = read_tet_mesh(dir / "sphere.mesh");
  EXPECT_EQ(j.at("points").get<size_t>(), mesh.points.size());
  EXPECT_EQ(j.at("tets").get<size_t>(), mesh.tets.size());
  EXPECT_GT(j.at("springs").get<int>(), j.at("points").get<int>());  // ~6.5 springs per point
  EXPECT_GT(j.at("quality").at("min_dihedral_deg").get<double>(), 0.0);
  // The histogram counts every point once.
  int total = 0;
  for (int count : j.at("springs_per_point").at("histogram")) total += count;
  EXPECT_EQ(total, j.at("points").get<int>());

  // Converting the written tet mesh (no remeshing) reports the same counts.
  const CliRun again = run_organsim("mesh " + (dir / "sphere.mesh").string() + " -o " + (dir / "sphere.vtk").string() +
                                     " --json", dir);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  const nlohmann::json k = nlohmann::json::parse(again.out);
  for (const char* key : {"points", "springs", "tets", "boundary_triangles"}) EXPECT_EQ(k.at(key), j.at(key)) << key;
}

TEST(MeshCli, MillimetreSurfaceIsScaledBeforeMeshingAndReportedInMetres) {
  const auto dir = fresh_test_dir("mesh_cli");
  TriangleMesh sphere_mm = make_sphere_surface(0.05, 3);
  for (Vec3& p : sphere_mm.points) p *= 1000.0;  // a 50 mm sphere, as a CT segmentation would give it
  write_surface(dir / "sphere_mm.vtk", sphere_mm);
  // --cell-size is in metres of the scaled surface: 12 mm cells on a 100 mm sphere.
  const CliRun run = run_organsim("mesh " + (dir / "sphere_mm.vtk").string() + " --units mm --cell-size 0.012 -o " +
                                      (dir / "sphere.vtu").string() + " --json", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  const std::string notes = j.at("notes").dump();
  EXPECT_NE(notes.find("input scaled by 0.001 (--units mm)"), std::string::npos) << notes;
  EXPECT_NE(notes.find("sizes in metres"), std::string::npos) << notes;
  const TetMesh mesh = read_tet_mesh(dir / "sphere.vtu");
  EXPECT_EQ(j.at("points").get<size_t>(), mesh.points.size());
  // Volume of the meshed sphere within 5 % of 4/3 pi (0.05 m)^3: the mesh
  // boundary is a polyhedral approximation (facet distance 1.2 mm).
  const double sphere_volume = 4.0 / 3.0 * 3.14159265358979 * 0.05 * 0.05 * 0.05;
  EXPECT_NEAR(tet_mesh_volume(mesh), sphere_volume, 0.05 * sphere_volume);
  // --scale 0.001 is the same as --units mm: the same mesh, point for point.
  const CliRun same = run_organsim("mesh " + (dir / "sphere_mm.vtk").string() + " --scale 0.001 --cell-size 0.012 -o " +
                                       (dir / "same.vtu").string(), dir);
  ASSERT_EQ(same.exit_code, 0) << same.err;
  const TetMesh again = read_tet_mesh(dir / "same.vtu");
  ASSERT_EQ(again.points.size(), mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) EXPECT_EQ(again.points[i], mesh.points[i]) << i;
  // Unknown units and --units with --scale are CLI11 parse errors; a bad scale is ours.
  EXPECT_NE(run_organsim("mesh " + (dir / "sphere_mm.vtk").string() + " --units inch -o " + (dir / "x.vtu").string(), dir).exit_code, 0);
  EXPECT_NE(run_organsim("mesh " + (dir / "sphere_mm.vtk").string() + " --units mm --scale 0.001 -o " + (dir / "x.vtu").string(), dir).exit_code, 0);
  EXPECT_EQ(run_organsim("mesh " + (dir / "sphere_mm.vtk").string() + " --scale -1 -o " + (dir / "x.vtu").string(), dir).exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.vtu"));
}

TEST(MeshCli, UsageErrorsExitWithTheUsageCode) {
  const auto dir = fresh_test_dir("mesh_cli");
  write_surface(dir / "sphere.off", make_sphere_surface(0.05, 1));
  // Unsupported output extension: refused before meshing, nothing written.
  CliRun run = run_organsim("mesh " + (dir / "sphere.off").string() + " -o " + (dir / "out.stl").string(), dir);
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("out.stl: output must end in .mesh (medit), .vtk (VTK legacy) or .vtu"), std::string::npos) << run.err;
  // --target-points and a cell size for everything exclude each other.
  run = run_organsim("mesh " + (dir / "sphere.off").string() + " -o " + (dir / "out.mesh").string() +
                         " --target-points 100 --cell-size 0.01", dir);
  EXPECT_EQ(run.exit_code, 2) << run.err;  // a crash (no exit status) or another code fails
  EXPECT_NE(run.err.find("give either a target point count or a cell size, not both"), std::string::npos) << run.err;
  EXPECT_EQ(other_files(dir, "sphere.off").size(), 0u);
}

// The phantom cut short as an interrupted download leaves it, to a third
// of its bytes and without only its 8-byte gzip trailer (CRC-32 and length):
// both are refused naming the file, and an existing output is left as it was.
TEST(MeshImageCli, AGzippedImageCutShortIsRefusedAndTheOldOutputKept) {
  const auto dir = testing::fresh_test_dir("mesh_image_cli_cut");
  const std::string phantom = read_text_file(std::string(ORGANSIM_SOURCE_DIR) + "/examples/phantom.nii.gz");
  write_fixture(dir / "out.vtu", "an earlier mesh");
  const std::pair<const char*, size_t> cuts[] = {{"third.nii.gz", phantom.size() / 3}, {"no_trailer.nii.gz", phantom.size() - 8}};
  for (const auto& [name, bytes] : cuts) {
    write_fixture(dir / name, phantom.substr(0, bytes));
    const CliRun r = run_organsim("mesh " + (dir / name).string() + " -o " + (dir / "out.vtu").string(), dir);
    EXPECT_EQ(r.exit_code, 3) << name << ": " << r.err;
    EXPECT_NE(r.err.find(std::string(name) + ": the gzip stream is cut short"), std::string::npos) << r.err;
    EXPECT_TRUE(read_text_file(dir / "out.vtu") == "an earlier mesh") << name << ": the earlier output was replaced";
  }
}

}  // namespace
}  // namespace mesh_cli_test
}  // namespace organsim

namespace organsim {
namespace mesh_cli_test {
namespace {

TEST(ExampleCli, RegeneratesTheCommittedExamplesByteForByte) {
  const auto dir = testing::fresh_test_dir("mesh_cli");
  for (const char* shape : {"liver", "sphere", "box"}) {
    const auto path = dir / (std::string(shape) + ".off");
    const CliRun run = run_organsim(std::string("example ") + shape + " -o " + path.string(), dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto committed = std::filesystem::path(ORGANSIM_SOURCE_DIR) / "examples" / (std::string(shape) + ".off");
    EXPECT_EQ(read_text_file(path), read_text_file(committed)) << shape << ": examples/ is out of date or the generator changed";
  }
}

}  // namespace
}  // namespace mesh_cli_test
}  // namespace organsim

namespace organsim {
namespace mesh_cli_test {
namespace {

TEST(MeshImageCli, LabelledImageGivesALabelledMeshAndVolumesPerLabel) {
  const auto dir = testing::fresh_test_dir("mesh_image_cli");
  const auto out = dir / "phantom.vtu";
  const CliRun run = run_organsim("mesh " + std::string(ORGANSIM_SOURCE_DIR) +
                                      "/examples/phantom.nii.gz --cell-size 0.004 --cell-size 2:0.002 --no-exude --json -o " +
                                      out.string(),
                                  dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json report = nlohmann::json::parse(run.out);  // CGAL's progress must not reach stdout
  ASSERT_EQ(report["labels"].size(), 2u);
  EXPECT_EQ(report["labels"][0]["label"], 1);
  EXPECT_EQ(report["labels"][1]["label"], 2);
  EXPECT_GT(report["labels"][1]["image_volume_m3"].get<double>(), 2e-6);
  const TetMesh mesh = read_tet_mesh(out);
  ASSERT_EQ(mesh.labels.size(), mesh.tets.size());
  EXPECT_EQ(static_cast<int>(std::count(mesh.labels.begin(), mesh.labels.end(), 2)), report["labels"][1]["tets"].get<int>());
}

TEST(MeshImageCli, BadImagesExitWithTheInputCodeAndWriteNothing) {
  const auto dir = testing::fresh_test_dir("mesh_image_cli_bad");
  const std::string phantom = std::string(ORGANSIM_SOURCE_DIR) + "/examples/phantom.nii.gz";
  const CliRun none = run_organsim("mesh " + phantom + " --labels 9 -o " + (dir / "out.vtu").string(), dir);
  EXPECT_EQ(none.exit_code, 3);
  EXPECT_NE(none.err.find("phantom.nii.gz: no voxel of the labels 9: it has labels 1 ("), std::string::npos) << none.err;
  write_fixture(dir / "garbage.nii", "this is not a NIfTI header");
  const CliRun garbage = run_organsim("mesh " + (dir / "garbage.nii").string() + " -o " + (dir / "out.vtu").string(), dir);
  EXPECT_EQ(garbage.exit_code, 3);
  EXPECT_NE(garbage.err.find("garbage.nii: not a readable NIfTI-1 file"), std::string::npos) << garbage.err;
  const CliRun per_label = run_organsim("mesh " + (std::string(ORGANSIM_SOURCE_DIR) + "/examples/sphere.off") +
                                            " --cell-size 2:0.01 -o " + (dir / "out.vtu").string(), dir);
  EXPECT_EQ(per_label.exit_code, 2);
  EXPECT_NE(per_label.err.find("a size per label is for labelled images only"), std::string::npos) << per_label.err;
  EXPECT_EQ(other_files(dir, "garbage.nii"), std::vector<std::string>{}) << "an output or temporary file was left";
}

}  // namespace
}  // namespace mesh_cli_test
}  // namespace organsim
