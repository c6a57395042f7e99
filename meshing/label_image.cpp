// Dispatch by extension and the checks every labelled-image reader shares.
#include "meshing/label_image.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

enum class ImageFormat { None, Nifti, Nrrd, Inr };

ImageFormat format_of(const std::filesystem::path& path) {
  const std::string name = lower(path.filename().string());
  if (ends_with(name, ".nii") || ends_with(name, ".nii.gz")) return ImageFormat::Nifti;
  if (ends_with(name, ".nrrd") || ends_with(name, ".nhdr")) return ImageFormat::Nrrd;
  if (ends_with(name, ".inr") || ends_with(name, ".inr.gz")) return ImageFormat::Inr;
  return ImageFormat::None;
}

}  // namespace

bool is_label_image_path(const std::filesystem::path& path) { return format_of(path) != ImageFormat::None; }

LabelImage read_label_image(const std::filesystem::path& path) {
  const std::string source = path.string();
  const ImageFormat format = format_of(path);
  if (format == ImageFormat::None) {
    throw input_error(source, "unknown image extension, expected .nii, .nii.gz, .nrrd, .nhdr, .inr or .inr.gz");
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw input_error(source, "cannot open: no such file");
  LabelImage image;
  if (format == ImageFormat::Nifti) image = image_io::read_nifti(path, source);
  if (format == ImageFormat::Nrrd) image = image_io::read_nrrd(path, source);
  if (format == ImageFormat::Inr) image = image_io::read_inr(path, source);
  if (!image.axes.allFinite() || !image.origin.allFinite()) {
    throw input_error(source, "the header's voxel spacing, direction or origin is not finite");
  }
  if (!(std::abs(image.axes.determinant()) > 0)) {
    throw input_error(source, "the header's voxel axes are degenerate (zero spacing or parallel directions)");
  }
  return image;
}

void apply_image_units(LabelImage& image, std::optional<double> metres_per_unit, const std::string& source) {
  double scale = 0;
  if (image.metres_per_unit) {
    scale = *image.metres_per_unit;
    if (metres_per_unit && std::abs(*metres_per_unit - scale) > 1e-12 * scale) {
      throw Error(ErrorKind::Usage, source + ": the header gives the unit " + image.unit_name + " (" +
                                        format_number(scale) + " m); --units/--scale " +
                                        format_number(*metres_per_unit) + " contradicts it: leave it out");
    }
  } else if (metres_per_unit) {
    scale = *metres_per_unit;
    image.notes.push_back("the header names no length unit: " + format_number(scale) + " m per unit (--units/--scale)");
  } else {
    throw Error(ErrorKind::Usage, source + ": the header names no length unit: give --units mm (or cm, m) or --scale");
  }
  image.axes *= scale;
  image.origin *= scale;
  image.metres_per_unit = 1.0;
}

std::map<int32_t, int64_t> label_voxel_counts(const LabelImage& image) {
  std::map<int32_t, int64_t> counts;
  for (int32_t l : image.labels) ++counts[l];
  return counts;
}

double voxel_volume(const LabelImage& image) { return std::abs(image.axes.determinant()); }

void select_labels(LabelImage& image, const std::vector<int32_t>& keep, const std::string& source) {
  const auto kept = [&](int32_t l) {
    return l > 0 && (keep.empty() || std::find(keep.begin(), keep.end(), l) != keep.end());
  };
  const std::map<int32_t, int64_t> before = label_voxel_counts(image);
  int64_t inside = 0;
  for (int32_t& l : image.labels) {
    if (!kept(l)) l = 0;
    inside += l != 0;
  }
  if (inside == 0) {
    std::ostringstream present;
    for (const auto& [l, n] : before) {
      if (l != 0) present << (present.tellp() > 0 ? ", " : "") << l << " (" << n << " voxels)";
    }
    const std::string has = present.tellp() > 0 ? "it has labels " + present.str() : "every voxel is 0 (outside)";
    std::ostringstream asked;
    for (int32_t l : keep) asked << (asked.tellp() > 0 ? "," : "") << l;
    throw input_error(source, std::string("no voxel of ") + (keep.empty() ? "any label > 0" : "the labels " + asked.str()) +
                                  ": " + has);
  }
}

namespace image_io {

int64_t max_data_bytes(int64_t file_bytes, bool compressed) {
  constexpr int64_t kDeflateMaxRatio = 1032;  // deflate's largest expansion (258-byte runs in 2 bits)
  return compressed ? file_bytes * kDeflateMaxRatio + 4096 : file_bytes;
}

void check_data_size(int64_t voxels, int bytes_per_voxel, int64_t max_bytes, const std::string& source) {
  if (voxels <= 0) throw input_error(source, "the header gives no voxels (a dimension is 0)");
  if (voxels > kMaxImageVoxels) {
    throw input_error(source, "the header gives " + std::to_string(voxels) + " voxels, more than organsim reads (" +
                                  std::to_string(kMaxImageVoxels) + ")");
  }
  if (voxels * bytes_per_voxel > max_bytes) {
    throw input_error(source, "the header gives " + std::to_string(voxels) + " voxels of " + std::to_string(bytes_per_voxel) +
                                  " bytes, more than the file's data can hold (at most " + std::to_string(max_bytes) +
                                  " bytes): the header does not match the data");
  }
}

template <class T>
std::vector<int32_t> copy_labels(const void* data, int64_t count, const std::string& source) {
  std::vector<int32_t> labels(static_cast<size_t>(count));
  const T* values = static_cast<const T*>(data);
  for (int64_t n = 0; n < count; ++n) {
    const T v = values[n];
    if constexpr (std::is_signed_v<T>) {
      if (v < 0) {
        throw input_error(source, "voxel " + std::to_string(n) + " has the negative label " + std::to_string(v) +
                                      ": labels are integers >= 0 (0 is outside)");
      }
    }
    if (static_cast<uint64_t>(v) > static_cast<uint64_t>(std::numeric_limits<int32_t>::max())) {
      throw input_error(source, "voxel " + std::to_string(n) + " has the label " + std::to_string(v) +
                                    ", above the largest label organsim keeps (2^31 - 1)");
    }
    labels[static_cast<size_t>(n)] = static_cast<int32_t>(v);
  }
  return labels;
}

template std::vector<int32_t> copy_labels<uint8_t>(const void*, int64_t, const std::string&);
template std::vector<int32_t> copy_labels<int8_t>(const void*, int64_t, const std::string&);
template std::vector<int32_t> copy_labels<uint16_t>(const void*, int64_t, const std::string&);
template std::vector<int32_t> copy_labels<int16_t>(const void*, int64_t, const std::string&);
template std::vector<int32_t> copy_labels<uint32_t>(const void*, int64_t, const std::string&);
template std::vector<int32_t> copy_labels<int32_t>(const void*, int64_t, const std::string&);
template std::vector<int32_t> copy_labels<uint64_t>(const void*, int64_t, const std::string&);
template std::vector<int32_t> copy_labels<int64_t>(const void*, int64_t, const std::string&);

}  // namespace image_io

}  // namespace organsim
