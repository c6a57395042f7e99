// CGAL's own labelled volumes (.inr, .inr.gz, INRIA's format, as in CGAL's
// Mesh_3 examples) through CGAL ImageIO: the library parses the header and
// reads (inflates, byte-swaps) the data; this file checks that it is a
// segmentation. The format names no length unit and no orientation: the
// axes are the spacings VX, VY, VZ, the origin TX, TY, TZ where given.
#include <CGAL/ImageIO.h>
#include <zlib.h>

#include <memory>
#include <string>
#include <string_view>

#include "core/util/error.h"
#include "meshing/gzip_stream.h"
#include "meshing/label_image.h"

namespace organsim::image_io {

namespace {

struct ImageFree {
  void operator()(_image* im) const { _freeImage(im); }
};

std::vector<int32_t> copy_inr_labels(const _image& im, int64_t count, const std::string& source) {
  if (im.wordKind != WK_FIXED) {
    throw input_error(source, "voxels of floating-point type: a segmentation stores integer labels");
  }
  const bool is_signed = im.sign == SGN_SIGNED;
  switch (im.wdim) {
    case 1: return is_signed ? copy_labels<int8_t>(im.data, count, source) : copy_labels<uint8_t>(im.data, count, source);
    case 2: return is_signed ? copy_labels<int16_t>(im.data, count, source) : copy_labels<uint16_t>(im.data, count, source);
    case 4: return is_signed ? copy_labels<int32_t>(im.data, count, source) : copy_labels<uint32_t>(im.data, count, source);
    case 8: return is_signed ? copy_labels<int64_t>(im.data, count, source) : copy_labels<uint64_t>(im.data, count, source);
    default: break;
  }
  throw input_error(source, "voxels of " + std::to_string(im.wdim) + " bytes: expected 1, 2, 4 or 8-byte integers");
}

// CGAL ImageIO picks its reader by the file's magic, whatever the file's
// name: a .inr that is really a PGM reached the PGM reader, which hung on a
// header the fuzzer made (tests/fuzz/regressions/inr). Only INR is read
// here: the file, inflated if gzipped, must start with INR's header line.
// An INR header is one or more blocks of 256 bytes.
constexpr int64_t kInrHeaderBytes = 256;

void require_inr_header(const std::filesystem::path& path, const std::string& source) {
  constexpr std::string_view kMagic = "#INRIMAGE-4#{";
  gzFile file = gzopen(path.c_str(), "rb");
  if (file == nullptr) throw input_error(source, "cannot open it");
  char head[kMagic.size()] = {};
  const int read = gzread(file, head, static_cast<unsigned>(kMagic.size()));
  gzclose(file);
  if (read != static_cast<int>(kMagic.size()) || std::string_view(head, kMagic.size()) != kMagic)
    throw input_error(source, "not an INR image: it does not start with \"#INRIMAGE-4#{\"");
}

}  // namespace

LabelImage read_inr(const std::filesystem::path& path, const std::string& source) {
  require_inr_header(path, source);
  int error = 0;
  std::unique_ptr<_image, ImageFree> im(_readImageHeaderAndGetError(path.c_str(), &error));
  if (!im || error != 0) throw input_error(source, "not a readable INR image (bad header)");
  if (im->vdim != 1) {
    throw input_error(source, std::to_string(im->vdim) + " values per voxel: a segmentation has one label per voxel");
  }
  LabelImage image;
  image.size = {static_cast<int64_t>(im->xdim), static_cast<int64_t>(im->ydim), static_cast<int64_t>(im->zdim)};
  for (int64_t s : image.size) {
    if (s <= 0 || s > kMaxImageVoxels) throw input_error(source, "the header gives a dimension of " + std::to_string(s) + " voxels");
  }
  std::error_code ec;
  const auto file_bytes = static_cast<int64_t>(std::filesystem::file_size(path, ec));
  if (ec) throw input_error(source, "cannot read its size: " + ec.message());
  check_data_size(image.voxel_count(), static_cast<int>(im->wdim), max_data_bytes(file_bytes, im->openMode == OM_GZ), source);
  if (is_gzip_file(path)) {
    // ImageIO inflates the data it needs and stops: a missing tail or
    // trailer would go unseen. The stream is read whole first.
    require_whole_gzip(path, source, 0, kInrHeaderBytes + image.voxel_count() * im->wdim,
                       "a header of at least " + std::to_string(kInrHeaderBytes) + " bytes + " + std::to_string(image.voxel_count()) +
                           " voxels of " + std::to_string(im->wdim) + " bytes");
  }
  if (_readImageData(im.get()) != 1) {
    throw input_error(source, "the voxel data is shorter than the header says (" + std::to_string(image.voxel_count()) +
                                  " voxels of " + std::to_string(im->wdim) + " bytes)");
  }
  image.labels = copy_inr_labels(*im, image.voxel_count(), source);
  image.axes = Eigen::Vector3d(im->vx, im->vy, im->vz).asDiagonal();
  image.origin = Vec3(im->tx, im->ty, im->tz);
  image.notes.push_back("INR: axis-aligned voxels (VX, VY, VZ), origin TX, TY, TZ");
  return image;
}

}  // namespace organsim::image_io
