// Labelled images: the NIfTI, NRRD and INR readers against what the test
// wrote (and against VTK's own readers), every bad image refused naming the
// file, and the labelled Mesh_3 mesh: labels kept, interfaces conforming,
// placement (spacing, rotation, origin) honoured, volumes per label.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "../core/mesh_io_test_util.h"
#include "../core/vtk_client.h"
#include "core/mesh/mesh_stats.h"
#include "meshing/label_image.h"
#include "meshing/mesh_image.h"
#include "tests/meshing/label_image_files.h"

namespace organsim {
namespace label_image_test {
namespace {

using testing::error_message;
using testing::fresh_test_dir;
using testing::write_fixture;

// 6 x 5 x 4 voxels, labels 0..3 in a pattern, spacing 0.5 x 0.8 x 1.2 mm,
// turned 30 degrees about z, origin (10, -5, 3) mm.
testing::TestVolume tilted_volume() {
  testing::TestVolume v = testing::empty_volume(6, 5, 4);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i) v.at(i, j, k) = static_cast<uint8_t>((i + 2 * j + 3 * k) % 4);
  const double a = std::numbers::pi / 6;
  Eigen::Matrix3d rotation;
  rotation << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  v.axes = rotation * Eigen::Vector3d(0.5, 0.8, 1.2).asDiagonal();
  v.origin = {10, -5, 3};
  return v;
}

void expect_same_voxels(const LabelImage& image, const testing::TestVolume& v) {
  ASSERT_EQ(image.size, (std::array<int64_t, 3>{v.size[0], v.size[1], v.size[2]}));
  ASSERT_EQ(image.labels.size(), v.labels.size());
  for (size_t n = 0; n < v.labels.size(); ++n) ASSERT_EQ(image.labels[n], v.labels[n]) << "voxel " << n;
}

// Placement in mm, as written; float precision (NIfTI stores floats).
void expect_placement(const LabelImage& image, const Eigen::Matrix3d& axes, const Eigen::Vector3d& origin, double tol) {
  EXPECT_LT((image.axes - axes).cwiseAbs().maxCoeff(), tol) << image.axes;
  EXPECT_LT((image.origin - origin).cwiseAbs().maxCoeff(), tol) << image.origin.transpose();
}

TEST(LabelImage, NiftiVoxelsPlacementAndUnitsAsWritten) {
  const auto dir = fresh_test_dir("label_image_nifti");
  const testing::TestVolume v = tilted_volume();
  for (const char* name : {"tilted.nii", "tilted.nii.gz"}) {
    testing::write_nifti(dir / name, v);
    LabelImage image = read_label_image(dir / name);
    expect_same_voxels(image, v);
    expect_placement(image, v.axes, v.origin, 1e-5);
    ASSERT_TRUE(image.metres_per_unit.has_value());
    EXPECT_EQ(*image.metres_per_unit, 1e-3);
    apply_image_units(image, std::nullopt, name);
    expect_placement(image, v.axes * 1e-3, v.origin * 1e-3, 1e-8);
  }
  // VTK's NIfTI reader sees the same grid, labels and sform.
  const std::string out = testing::run_vtk_python(
      "r = vtk.vtkNIFTIImageReader()\nr.SetFileName('tilted.nii')\nr.Update()\n"
      "img = r.GetOutput()\nprint(*img.GetDimensions())\n"
      "a = img.GetPointData().GetScalars()\nprint(sum(a.GetValue(i) for i in range(a.GetNumberOfTuples())))\n"
      "m = r.GetSFormMatrix()\nprint(*[m.GetElement(i, j) for i in range(3) for j in range(4)])\n"
      "print(*img.GetSpacing())\n",
      dir);
  std::istringstream in(out);
  int nx = 0, ny = 0, nz = 0;
  long sum = 0;
  in >> nx >> ny >> nz >> sum;
  EXPECT_EQ(nx, 6);
  EXPECT_EQ(ny, 5);
  EXPECT_EQ(nz, 4);
  long expected_sum = 0;
  for (uint8_t l : v.labels) expected_sum += l;
  EXPECT_EQ(sum, expected_sum);
  // VTK splits the sform into a rotation (the matrix) and the spacing.
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) in >> rotation(r, c);
    in >> translation[r];
  }
  Eigen::Vector3d spacing;
  in >> spacing[0] >> spacing[1] >> spacing[2];
  const LabelImage ours = read_label_image(dir / "tilted.nii");
  EXPECT_LT((rotation * spacing.asDiagonal() - ours.axes).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT((translation - ours.origin).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(LabelImage, NrrdInLpsBecomesRasAndAgreesWithVtk) {
  const auto dir = fresh_test_dir("label_image_nrrd");
  const testing::TestVolume v = tilted_volume();
  const Eigen::Matrix3d lps_to_ras = Eigen::Vector3d(-1, -1, 1).asDiagonal();
  testing::write_nrrd(dir / "tilted.nrrd", v, "left-posterior-superior");
  testing::write_nrrd(dir / "tilted.nhdr", v, "left-posterior-superior", /*detached=*/true);
  for (const char* name : {"tilted.nrrd", "tilted.nhdr"}) {
    const LabelImage image = read_label_image(dir / name);
    expect_same_voxels(image, v);
    expect_placement(image, lps_to_ras * v.axes, lps_to_ras * v.origin, 1e-12);
    EXPECT_EQ(image.metres_per_unit.value_or(0), 1e-3);
  }
  // In RAS it is taken as written.
  testing::write_nrrd(dir / "ras.nrrd", v, "right-anterior-superior");
  expect_placement(read_label_image(dir / "ras.nrrd"), v.axes, v.origin, 1e-12);
  // VTK's own NRRD reader reads the same bytes (its MPI variant, which
  // `import vtk` puts in its place, is switched off). VTK 9.1 takes the
  // fastest axis as components for a 3D scalar file, so the check is on
  // every value, not on the grid.
  const std::string out = testing::run_vtk_python(
      "vtk.vtkObjectFactory.SetAllEnableFlags(False, 'vtkNrrdReader')\n"
      "from vtkmodules.vtkIOImage import vtkNrrdReader\n"
      "r = vtkNrrdReader()\nr.SetFileName('tilted.nrrd')\nr.Update()\n"
      "a = r.GetOutput().GetPointData().GetScalars()\nn = a.GetNumberOfTuples() * a.GetNumberOfComponents()\n"
      "print(n, sum(a.GetValue(i) for i in range(n)))\n",
      dir);
  std::istringstream in(out);
  long count = 0, sum = 0;
  in >> count >> sum;
  EXPECT_EQ(count, 120);
  long expected_sum = 0;
  for (uint8_t l : v.labels) expected_sum += l;
  EXPECT_EQ(sum, expected_sum);
}

TEST(LabelImage, SlicerSegNrrdGivesSegmentNames) {
  const auto dir = fresh_test_dir("label_image_seg");
  const testing::TestVolume v = tilted_volume();
  testing::write_nrrd(dir / "liver.seg.nrrd", v, "left-posterior-superior", false,
                      "Segment0_LabelValue:=1\nSegment0_Name:=parenchyma\nSegment1_LabelValue:=2\n"
                      "Segment1_Name:=tumour\nSegment2_LabelValue:=3\nSegment2_Name:=vessels\n");
  const LabelImage image = read_label_image(dir / "liver.seg.nrrd");
  expect_same_voxels(image, v);
  EXPECT_EQ(image.names, (std::map<int32_t, std::string>{{1, "parenchyma"}, {2, "tumour"}, {3, "vessels"}}));
}

TEST(LabelImage, InrSpacingAsWrittenAndNoUnitNeedsOne) {
  const auto dir = fresh_test_dir("label_image_inr");
  testing::TestVolume v = tilted_volume();
  v.axes = Eigen::Vector3d(0.5, 0.8, 1.2).asDiagonal();
  testing::write_inr(dir / "grid.inr", v);
  LabelImage image = read_label_image(dir / "grid.inr");
  expect_same_voxels(image, v);
  expect_placement(image, v.axes, Eigen::Vector3d::Zero(), 1e-6);
  EXPECT_FALSE(image.metres_per_unit.has_value());
  const std::string message = error_message([&] { apply_image_units(image, std::nullopt, "grid.inr"); });
  EXPECT_NE(message.find("grid.inr: the header names no length unit: give --units"), std::string::npos) << message;
  apply_image_units(image, 1e-3, "grid.inr");
  expect_placement(image, v.axes * 1e-3, Eigen::Vector3d::Zero(), 1e-9);
}

TEST(LabelImage, BadImagesAreRefusedNamingTheFileAndTheProblem) {
  const auto dir = fresh_test_dir("label_image_bad");
  const testing::TestVolume v = tilted_volume();
  const auto refused = [&](const std::filesystem::path& path, const std::string& expected) {
    const std::string message = error_message([&] { read_label_image(path); });
    EXPECT_NE(message.find(path.string() + ": "), std::string::npos) << message;
    EXPECT_NE(message.find(expected), std::string::npos) << "expected '" << expected << "' in: " << message;
  };
  testing::NiftiOptions flat;
  flat.dims = {2, 6, 20, 1, 1, 1, 1, 1};
  testing::write_nifti(dir / "flat.nii", v, flat);
  refused(dir / "flat.nii", "2D image");
  testing::NiftiOptions series;
  series.dims = {4, 6, 5, 2, 2, 1, 1, 1};
  testing::write_nifti(dir / "series.nii", v, series);
  refused(dir / "series.nii", "4D image with 2 volumes");
  testing::NiftiOptions real;
  real.datatype = 16;
  testing::write_nifti(dir / "float.nii", v, real);
  refused(dir / "float.nii", "voxels of type FLOAT32");
  testing::NiftiOptions cut;
  cut.keep_bytes = 352 + 50;  // 120 voxels promised
  testing::write_nifti(dir / "short.nii", v, cut);
  refused(dir / "short.nii", "the header does not match the data");
  // Attached data: teem finds it short (the header's length is its to know).
  testing::write_nrrd(dir / "short.nrrd", v, "right-anterior-superior", false, "", "", 50);
  refused(dir / "short.nrrd", "cannot read the voxel data");
  testing::write_nrrd(dir / "short.nhdr", v, "right-anterior-superior", true, "", "", 50);
  refused(dir / "short.nhdr", "the header does not match the data");
  testing::write_nrrd(dir / "layers.seg.nrrd", v, "right-anterior-superior", false, "", "2 3 5 4");
  refused(dir / "layers.seg.nrrd", "several layers");
  write_fixture(dir / "garbage.nrrd", "NRRD0004\nthis is not a header\n");
  refused(dir / "garbage.nrrd", "not a readable NRRD file");
  write_fixture(dir / "garbage.nii", "not a nifti header");
  refused(dir / "garbage.nii", "not a readable NIfTI-1 file");
  refused(dir / "missing.nii.gz", "no such file");
  // Found by the fuzzer (tests/fuzz/regressions/nifti): 353 bytes whose
  // header claims 455 M voxels at vox_offset -4e37; the size check must not
  // be fooled by the offset (the library allocated the voxels).
  refused(std::filesystem::path(ORGANSIM_SOURCE_DIR) / "tests/fuzz/regressions/nifti/negative_vox_offset.nii",
          "lies outside the file");
  // Also found by the fuzzer: a .inr that is a PGM inside hung CGAL's PGM reader.
  refused(std::filesystem::path(ORGANSIM_SOURCE_DIR) / "tests/fuzz/regressions/inr/pgm_inside.inr",
          "not an INR image");
}

TEST(LabelImage, NoVoxelOfTheAskedLabelsListsTheLabelsThere) {
  LabelImage image;
  image.size = {2, 1, 1};
  image.labels = {0, 4};
  const std::string message = error_message([&] { select_labels(image, {2, 3}, "seg.nii"); });
  EXPECT_NE(message.find("seg.nii: no voxel of the labels 2,3: it has labels 4 (1 voxels)"), std::string::npos) << message;
  image.labels = {0, 0};
  EXPECT_NE(error_message([&] { select_labels(image, {}, "empty.nii"); }).find("every voxel is 0"), std::string::npos);
  image.labels = {2, 4};
  select_labels(image, {4}, "seg.nii");
  EXPECT_EQ(image.labels, (std::vector<int32_t>{0, 4}));
}

// Two labels: a block of label 2 inside a block of label 1.
LabelImage nested_blocks(int n, int inner_lo, int inner_hi) {
  LabelImage image;
  image.size = {n, n, n};
  image.labels.assign(static_cast<size_t>(n) * n * n, 1);
  for (int k = inner_lo; k < inner_hi; ++k)
    for (int j = inner_lo; j < inner_hi; ++j)
      for (int i = inner_lo; i < inner_hi; ++i) image.labels[static_cast<size_t>(i + n * (j + n * k))] = 2;
  image.metres_per_unit = 1e-3;
  image.unit_name = "mm";
  return image;
}

TEST(LabelImageMesh, InterfacesAreConformingAndEveryTetHasItsLabel) {
  ImageMeshOptions options;
  options.cell_size = 0.003;
  options.exude = false;
  MeshReport report;
  const TetMesh mesh = mesh_label_image(nested_blocks(16, 5, 11), options, "blocks", &report);
  ASSERT_EQ(mesh.labels.size(), mesh.tets.size());
  // Each face (sorted corners) -> the labels of the tets that have it.
  std::map<std::array<int32_t, 3>, std::vector<int32_t>> faces;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int32_t, 3> f{};
      int n = 0;
      for (int k = 0; k < 4; ++k)
        if (k != skip) f[n++] = mesh.tets[t][k];
      std::sort(f.begin(), f.end());
      faces[f].push_back(mesh.labels[t]);
    }
  }
  size_t interface = 0, bad = 0;
  for (const auto& [f, labels] : faces) {
    if (labels.size() > 2) ++bad;
    if (labels.size() == 2 && labels[0] != labels[1]) {
      ++interface;
      if (std::min(labels[0], labels[1]) != 1 || std::max(labels[0], labels[1]) != 2) ++bad;
    }
    // A face of the inner label on its own is a gap in the interface: the
    // inner block touches nothing but label 1.
    if (labels.size() == 1 && labels[0] == 2) ++bad;
  }
  EXPECT_EQ(bad, 0u);
  EXPECT_GT(interface, 50u);
  // Interface area ~ the inner block's surface (6 x 6 mm faces): the
  // interface is the whole cube, not a patch.
  double area = 0;
  for (const auto& [f, labels] : faces) {
    if (labels.size() == 2 && labels[0] != labels[1]) {
      area += 0.5 * (mesh.points[f[1]] - mesh.points[f[0]]).cross(mesh.points[f[2]] - mesh.points[f[0]]).norm();
    }
  }
  // 20 %: the mesher rounds the edges and corners of a cube 6 voxels wide
  // over about a voxel (measured: 16 % less area than the cube's).
  EXPECT_NEAR(area, 6 * 36e-6, 0.2 * 6 * 36e-6);
  ASSERT_EQ(report.labels.size(), 2u);
  EXPECT_EQ(report.labels[0].label, 1);
  EXPECT_EQ(report.labels[1].label, 2);
  EXPECT_NEAR(report.labels[1].image_volume.value_or(0), 216e-9, 1e-15);
}

TEST(LabelImageMesh, SpacingRotationAndOriginPlaceTheMesh) {
  // A 20 x 6 x 4 bar of label 1 filling the image, spacing 0.5 x 0.8 x 1.2
  // mm, turned 30 degrees about z, origin (10, -5, 3) mm.
  LabelImage image;
  image.size = {20, 6, 4};
  image.labels.assign(20 * 6 * 4, 1);
  const testing::TestVolume tilted = tilted_volume();
  image.axes = tilted.axes;
  image.origin = tilted.origin;
  image.metres_per_unit = 1e-3;
  ImageMeshOptions options;
  options.cell_size = 0.001;
  options.exude = false;
  const TetMesh mesh = mesh_label_image(image, options, "bar");
  // The voxel block spans index -0.5 .. n - 0.5 on each axis: its corners in the world, m.
  Vec3 lo = Vec3::Constant(1e9), hi = -lo;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 index((corner & 1 ? 19.5 : -0.5), (corner & 2 ? 5.5 : -0.5), (corner & 4 ? 3.5 : -0.5));
    const Vec3 p = 1e-3 * (image.origin + image.axes * index);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Vec3 mlo = mesh.points.front(), mhi = mlo;
  for (const Vec3& p : mesh.points) {
    mlo = mlo.cwiseMin(p);
    mhi = mhi.cwiseMax(p);
  }
  // Within 0.4 mm (a third of the largest spacing): the mesher rounds the
  // block's corners, which pulls the box of a rotated block in a little. An
  // unrotated block would be 1.4 mm off in x, a missing origin 10 mm.
  EXPECT_LT((mlo - lo).cwiseAbs().maxCoeff(), 4e-4) << mlo.transpose() << " vs " << lo.transpose();
  EXPECT_LT((mhi - hi).cwiseAbs().maxCoeff(), 4e-4) << mhi.transpose() << " vs " << hi.transpose();
  // Volume: 20 x 6 x 4 voxels of 0.48 mm^3, within 8 %: the rounded edges
  // of a bar 4 voxels thick take about 6 % (a missing spacing would be 2x off).
  EXPECT_NEAR(tet_mesh_volume(mesh), 480 * 0.48e-9, 0.08 * 480 * 0.48e-9);
}

TEST(LabelImageMesh, PhantomLabelVolumesMatchTheAnalyticShapes) {
  // examples/phantom.nii.gz (scripts/make_phantom.py): a 40 x 40 x 30 mm box
  // (label 1) holding a sphere of radius 8 mm (label 2), 0.5 mm voxels.
  ImageMeshOptions options;
  options.cell_size = 0.003;
  options.label_cell_size[2] = 0.0015;
  MeshReport report;
  const TetMesh mesh = mesh_image_file(std::string(ORGANSIM_SOURCE_DIR) + "/examples/phantom.nii.gz", options, &report);
  const double sphere = 4.0 / 3.0 * std::numbers::pi * std::pow(0.008, 3);
  const double box = 0.04 * 0.04 * 0.03;
  ASSERT_EQ(report.labels.size(), 2u);
  // 3 %: the sphere's voxels are 0.5 mm steps on a 8 mm radius (their
  // union is within ~1 % of the ball), and the mesh follows them.
  EXPECT_NEAR(report.labels[0].mesh_volume, box - sphere, 0.03 * (box - sphere));
  EXPECT_NEAR(report.labels[1].mesh_volume, sphere, 0.03 * sphere);
  EXPECT_TRUE(report.warnings.empty()) << report.warnings.front();
  // The finer sphere has smaller tets than the box.
  double vol[3] = {0, 0, 0};
  int count[3] = {0, 0, 0};
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& k = mesh.tets[t];
    vol[mesh.labels[t]] += signed_volume(mesh.points[k[0]], mesh.points[k[1]], mesh.points[k[2]], mesh.points[k[3]]);
    ++count[mesh.labels[t]];
  }
  EXPECT_LT(vol[2] / count[2], 0.5 * vol[1] / count[1]);
}

// Mean tet volume of one label, m^3.
double mean_tet_volume(const TetMesh& mesh, int32_t label) {
  double volume = 0;
  int count = 0;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    if (mesh.labels[t] != label) continue;
    const Tet& k = mesh.tets[t];
    volume += signed_volume(mesh.points[k[0]], mesh.points[k[1]], mesh.points[k[2]], mesh.points[k[3]]);
    ++count;
  }
  return volume / count;
}

TEST(LabelImageMesh, TargetPointsSizeTheLabelsWithoutTheirOwnCellSize) {
  // A 24 mm cube (label 1) around an 8 mm cube (label 2) held at 1 mm cells,
  // at two targets: the count lands within 10 % of each, label 2's cells keep
  // their size (mean tet volume within 25 %: Mesh_3 refines the interface a
  // little differently next to coarser or finer outer cells), label 1's grow
  // for the smaller target.
  const LabelImage image = nested_blocks(24, 8, 16);
  ImageMeshOptions options;
  options.label_cell_size[2] = 0.001;
  options.exude = false;
  double inner[2], outer[2];
  for (int k = 0; k < 2; ++k) {
    options.target_points = k == 0 ? 1500 : 3000;
    MeshReport report;
    const TetMesh mesh = mesh_label_image(image, options, "blocks", &report);
    EXPECT_NEAR(double(mesh.points.size()), *options.target_points, 0.1 * *options.target_points);
    inner[k] = mean_tet_volume(mesh, 2);
    outer[k] = mean_tet_volume(mesh, 1);
    // The inner label's cells are finer than the outer's the target chose.
    EXPECT_LT(inner[k], 0.5 * outer[k]) << "target " << *options.target_points;
  }
  EXPECT_NEAR(inner[1] / inner[0], 1.0, 0.25);
  EXPECT_GT(outer[0] / outer[1], 1.4);
  // Every meshed label sized: nothing left for the target to choose.
  options.label_cell_size[1] = 0.003;
  EXPECT_NE(error_message([&] { mesh_label_image(image, options, "blocks"); }).find("every meshed label has its own"),
            std::string::npos);
  // A cell size for all labels and a target: refused as for surfaces.
  options.label_cell_size.erase(1);
  options.cell_size = 0.003;
  EXPECT_NE(error_message([&] { mesh_label_image(image, options, "blocks"); }).find("not both"), std::string::npos);
}

}  // namespace
}  // namespace label_image_test
}  // namespace organsim
