#pragma once
// Labelled volumes (segmentations): NIfTI-1 (.nii, .nii.gz) through
// libniftiio, NRRD (.nrrd, .nhdr, 3D Slicer's .seg.nrrd) through teem, and
// CGAL's .inr/.inr.gz through CGAL ImageIO. Each reader checks what a
// segmentation must be (one 3D volume of non-negative integers whose data
// matches its header) and hands back the voxels with their placement in
// space; everything else about meshing an image is in mesh_image.h.
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/util/vec.h"

namespace organsim {

struct LabelImage {
  std::array<int64_t, 3> size{};  // voxels along the index axes i, j, k
  std::vector<int32_t> labels;    // size[0] * size[1] * size[2] values, i fastest, then j, then k
  // Placement: the centre of voxel (i, j, k) is at origin + axes * (i, j, k).
  // Column c of `axes` is the step along index axis c (spacing times
  // direction). In the file's unit until apply_image_units, then in metres;
  // right-anterior-superior (RAS, NIfTI's world frame) for NIfTI and for NRRD
  // files in a named anatomical space (an LPS file is turned into RAS).
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Vec3 origin = Vec3::Zero();
  std::optional<double> metres_per_unit;  // from the header; empty when it names no unit
  std::string unit_name;                  // the header's unit as written ("mm"), for messages
  std::map<int32_t, std::string> names;   // label -> segment name (.seg.nrrd)
  std::vector<std::string> notes;         // what the reader decided ("sform used", ...)

  int64_t voxel_count() const { return size[0] * size[1] * size[2]; }
  int32_t at(int64_t i, int64_t j, int64_t k) const { return labels[static_cast<size_t>(i + size[0] * (j + size[1] * k))]; }
};

// Largest image read: 2^30 voxels (a 1024^3 volume; a CT segmentation is
// typically 512 x 512 x 600). Refused above, before its data is allocated.
constexpr int64_t kMaxImageVoxels = int64_t{1} << 30;

// .nii .nii.gz .nrrd .nhdr .inr .inr.gz (.seg.nrrd ends in .nrrd).
bool is_label_image_path(const std::filesystem::path& path);

// Reads and checks a labelled volume, by extension. Throws Error(Input)
// naming the file: unknown extension, unreadable, not 3D (2D, or 4D with
// more than one volume), not integer, negative labels, data shorter than the
// header says, more than kMaxImageVoxels voxels.
LabelImage read_label_image(const std::filesystem::path& path);

// Turns the placement into metres: the header's unit when it names one
// (`metres_per_unit` given as well must agree with it), else
// `metres_per_unit`, else Error(Usage) asking for --units.
void apply_image_units(LabelImage& image, std::optional<double> metres_per_unit, const std::string& source);

// Keeps the voxels whose label is in `keep` (all labels > 0 when empty) and
// sets every other voxel to 0 (outside). Throws Error(Input) naming `source`
// when no voxel is left, listing the labels the image has.
void select_labels(LabelImage& image, const std::vector<int32_t>& keep, const std::string& source);

// Voxel count per label (0 included), ascending by label.
std::map<int32_t, int64_t> label_voxel_counts(const LabelImage& image);

// Volume of one voxel, |det(axes)| (m^3 after apply_image_units).
double voxel_volume(const LabelImage& image);

namespace image_io {
// The per-format readers behind read_label_image; `source` names the file.
LabelImage read_nifti(const std::filesystem::path& path, const std::string& source);
LabelImage read_nrrd(const std::filesystem::path& path, const std::string& source);
LabelImage read_inr(const std::filesystem::path& path, const std::string& source);

// Bounds used by the readers before any allocation: a file of `file_bytes`
// can hold at most this many bytes of voxel data (deflate expands at most
// ~1032x; a gzip-compressed file is `compressed`).
int64_t max_data_bytes(int64_t file_bytes, bool compressed);
// Throws unless 0 < voxels <= kMaxImageVoxels and voxels * bytes_per_voxel
// fit in `max_bytes`.
void check_data_size(int64_t voxels, int bytes_per_voxel, int64_t max_bytes, const std::string& source);
// Copies integer voxels of type T, refusing negative values and values above
// INT32_MAX with the first offending voxel named.
template <class T>
std::vector<int32_t> copy_labels(const void* data, int64_t count, const std::string& source);
}  // namespace image_io

}  // namespace organsim
