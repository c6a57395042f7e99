// NRRD labelled volumes (.nrrd, .nhdr with detached data, 3D Slicer's
// .seg.nrrd) through Debian's teem: the library parses the header and reads
// (and decodes, byte-swaps) the data; this file checks that it is a
// segmentation and takes its placement and Slicer's segment names.
#include <teem/nrrd.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>

#include "core/util/error.h"
#include "meshing/gzip_stream.h"
#include "meshing/label_image.h"

namespace organsim::image_io {

namespace {

struct NrrdFree {
  void operator()(Nrrd* nrrd) const { nrrdNuke(nrrd); }
};
struct IoStateFree {
  void operator()(NrrdIoState* nio) const { nrrdIoStateNix(nio); }
};
struct CFree {
  void operator()(char* s) const { std::free(s); }
};
using CString = std::unique_ptr<char, CFree>;

// teem keeps its error messages in the "biff" stack of its nrrd library.
std::string teem_error() {
  CString message(biffGetDone(NRRD));
  std::string text = message ? message.get() : "unknown error";
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return text;
}

std::vector<int32_t> copy_nrrd_labels(const Nrrd& nrrd, int64_t count, const std::string& source) {
  switch (nrrd.type) {
    case nrrdTypeUChar: return copy_labels<uint8_t>(nrrd.data, count, source);
    case nrrdTypeChar: return copy_labels<int8_t>(nrrd.data, count, source);
    case nrrdTypeUShort: return copy_labels<uint16_t>(nrrd.data, count, source);
    case nrrdTypeShort: return copy_labels<int16_t>(nrrd.data, count, source);
    case nrrdTypeUInt: return copy_labels<uint32_t>(nrrd.data, count, source);
    case nrrdTypeInt: return copy_labels<int32_t>(nrrd.data, count, source);
    case nrrdTypeULLong: return copy_labels<uint64_t>(nrrd.data, count, source);
    case nrrdTypeLLong: return copy_labels<int64_t>(nrrd.data, count, source);
    default: break;
  }
  throw input_error(source, std::string("voxels of type ") + airEnumStr(nrrdType, nrrd.type) +
                                ": a segmentation stores integer labels (uchar, short, ..., long long)");
}

// The header's three image axes: a 4D file whose extra axis has one sample
// (a single-layer .seg.nrrd written as 4D) is a 3D volume.
std::array<unsigned, 3> spatial_axes(const Nrrd& nrrd, const std::string& source) {
  const unsigned dim = nrrd.dim;
  if (dim == 3) return {0, 1, 2};
  if (dim == 4 && nrrd.axis[0].size == 1) return {1, 2, 3};
  if (dim == 4 && nrrd.axis[3].size == 1) return {0, 1, 2};
  if (dim == 4) {
    throw input_error(source, "4D image with " + std::to_string(nrrd.axis[0].size) +
                                  " samples on its first axis: a segmentation with overlapping segments in several "
                                  "layers; organsim meshes one 3D volume of labels (in 3D Slicer, export the "
                                  "segments to a labelmap volume, or keep them from overlapping so they share "
                                  "one layer)");
  }
  throw input_error(source, std::to_string(dim) + "D image: a segmentation for meshing is a 3D volume");
}

// Sum of the sizes of the files the data is in (the file itself, or the
// detached data files of an .nhdr), or -1 when they cannot be listed.
int64_t data_file_bytes(const std::filesystem::path& path, const NrrdIoState& nio) {
  std::error_code ec;
  if (nio.dataFNArr == nullptr || nio.dataFNArr->len == 0) {
    const auto bytes = std::filesystem::file_size(path, ec);
    return ec ? -1 : static_cast<int64_t>(bytes);
  }
  if (nio.dataFNFormat != nullptr) return -1;
  int64_t total = 0;
  for (unsigned i = 0; i < nio.dataFNArr->len; ++i) {
    std::filesystem::path file(nio.dataFN[i]);
    if (file.is_relative()) file = path.parent_path() / file;
    const auto bytes = std::filesystem::file_size(file, ec);
    if (ec) return -1;  // teem names the missing file below
    total += static_cast<int64_t>(bytes);
  }
  return total;
}

// teem inflates the voxels it needs and stops there: a gzip stream missing
// its tail or its trailer (CRC-32, length) reads as whole. Each stream is
// read to its end first. The data follows the header's first empty line in
// the file itself, or fills the detached data files (without skips).
constexpr size_t kMaxHeaderBytes = 1 << 20;  // a NRRD header is a few hundred bytes of text

void require_whole_gzip_data(const std::filesystem::path& path, const NrrdIoState& nio, int64_t data_bytes,
                             const std::string& source) {
  const std::string what = std::to_string(data_bytes) + " bytes of voxels";
  if (nio.dataFNArr == nullptr || nio.dataFNArr->len == 0) {
    std::ifstream in(path, std::ios::binary);
    std::string text(kMaxHeaderBytes, '\0');
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    text.resize(static_cast<size_t>(in.gcount()));
    size_t end = text.find("\n\n");
    size_t crlf = text.find("\r\n\r\n");
    if (end == std::string::npos && crlf == std::string::npos) {
      throw input_error(source, "no empty line ends the header within its first MiB");
    }
    const int64_t offset = crlf < end ? static_cast<int64_t>(crlf + 4) : static_cast<int64_t>(end + 2);
    require_whole_gzip(path, source, offset, data_bytes, what);
    return;
  }
  if (nio.dataFNArr->len != 1 || nio.lineSkip != 0 || nio.byteSkip != 0) return;  // teem's own checks only
  std::filesystem::path file(nio.dataFN[0]);
  if (file.is_relative()) file = path.parent_path() / file;
  require_whole_gzip(file, file.string(), 0, data_bytes, what);
}

// 3D Slicer's .seg.nrrd: "SegmentN_LabelValue" and "SegmentN_Name" for N = 0, 1, ...
void read_segment_names(const Nrrd& nrrd, LabelImage& image, const std::string& source) {
  for (int n = 0;; ++n) {
    const std::string key = "Segment" + std::to_string(n) + "_";
    CString value(nrrdKeyValueGet(&nrrd, (key + "LabelValue").c_str()));
    if (!value) return;
    const std::string text = value.get();
    int32_t label = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), label);
    if (ec != std::errc() || end != text.data() + text.size() || label <= 0) {
      throw input_error(source, key + "LabelValue is '" + text + "', expected an integer label > 0");
    }
    CString name(nrrdKeyValueGet(&nrrd, (key + "Name").c_str()));
    image.names[label] = name ? name.get() : key.substr(0, key.size() - 1);
  }
}

void take_placement(const Nrrd& nrrd, const std::array<unsigned, 3>& axes, LabelImage& image, const std::string& source) {
  if (nrrd.spaceDim == 0) {
    for (int c = 0; c < 3; ++c) {
      const double spacing = nrrd.axis[axes[c]].spacing;
      image.axes(c, c) = std::isfinite(spacing) && spacing != 0 ? spacing : 1.0;
    }
    image.notes.push_back("no space directions: axis spacings only, voxel (0, 0, 0) at the origin");
    return;
  }
  if (nrrd.spaceDim != 3) {
    throw input_error(source, "a " + std::to_string(nrrd.spaceDim) + "-dimensional space: expected a 3D space");
  }
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) image.axes(r, c) = nrrd.axis[axes[c]].spaceDirection[r];
  }
  for (int r = 0; r < 3; ++r) image.origin[r] = std::isfinite(nrrd.spaceOrigin[r]) ? nrrd.spaceOrigin[r] : 0.0;
  // Anatomical spaces are turned into RAS, NIfTI's world frame (and what 3D
  // Slicer shows), so a segmentation saved as NRRD or NIfTI lands in one place.
  Eigen::Vector3d flip(1, 1, 1);
  switch (nrrd.space) {
    case nrrdSpaceLeftPosteriorSuperior:
    case nrrdSpaceScannerXYZ: flip = {-1, -1, 1}; break;
    case nrrdSpaceLeftAnteriorSuperior: flip = {-1, 1, 1}; break;
    case nrrdSpaceRightAnteriorSuperior: break;
    default: image.notes.push_back("space is not anatomical: its coordinates are used as they are"); break;
  }
  if (flip != Eigen::Vector3d(1, 1, 1)) {
    image.axes = flip.asDiagonal() * image.axes;
    image.origin = flip.asDiagonal() * image.origin;
    image.notes.push_back(std::string("space ") + airEnumStr(nrrdSpace, nrrd.space) + " turned into right-anterior-superior");
  }
  const char* unit = nrrd.spaceUnits[0];
  if (unit != nullptr && *unit != 0) {
    for (int r = 1; r < 3; ++r) {
      if (nrrd.spaceUnits[r] == nullptr || std::string(nrrd.spaceUnits[r]) != unit) {
        throw input_error(source, "space units differ between axes; expected one length unit");
      }
    }
    const std::string u = unit;
    image.unit_name = u;
    if (u == "mm" || u == "millimeter" || u == "millimeters") image.metres_per_unit = 1e-3;
    else if (u == "cm" || u == "centimeter" || u == "centimeters") image.metres_per_unit = 1e-2;
    else if (u == "m" || u == "meter" || u == "meters") image.metres_per_unit = 1.0;
    else if (u == "um" || u == "micron" || u == "microns") image.metres_per_unit = 1e-6;
    else throw input_error(source, "space units '" + u + "': expected mm, cm, m or um");
  }
}

}  // namespace

LabelImage read_nrrd(const std::filesystem::path& path, const std::string& source) {
  // The header alone first (skipData): nothing is allocated for the data
  // until its size is checked against the files that hold it.
  std::unique_ptr<Nrrd, NrrdFree> header(nrrdNew());
  std::unique_ptr<NrrdIoState, IoStateFree> nio(nrrdIoStateNew());
  nio->skipData = AIR_TRUE;
  if (nrrdLoad(header.get(), path.c_str(), nio.get()) != 0) {
    throw input_error(source, "not a readable NRRD file: " + teem_error());
  }
  const std::array<unsigned, 3> axes = spatial_axes(*header, source);
  LabelImage image;
  int64_t voxels = 1;
  for (unsigned a = 0; a < header->dim; ++a) voxels *= static_cast<int64_t>(header->axis[a].size);
  for (int c = 0; c < 3; ++c) image.size[c] = static_cast<int64_t>(header->axis[axes[c]].size);
  if (header->type <= nrrdTypeUnknown || header->type >= nrrdTypeBlock) {
    throw input_error(source, "voxels of block type: a segmentation stores integer labels");
  }
  const int64_t file_bytes = data_file_bytes(path, *nio);
  const bool bzip2 = nio->encoding == nrrdEncodingBzip2;  // no useful bound on its expansion
  const int64_t max_bytes = file_bytes < 0 || bzip2 ? INT64_MAX / 2 : max_data_bytes(file_bytes, nio->encoding->isCompression);
  check_data_size(voxels, static_cast<int>(nrrdTypeSize[header->type]), max_bytes, source);

  if (nio->encoding == nrrdEncodingGzip) require_whole_gzip_data(path, *nio, voxels * nrrdTypeSize[header->type], source);

  std::unique_ptr<Nrrd, NrrdFree> nrrd(nrrdNew());
  if (nrrdLoad(nrrd.get(), path.c_str(), nullptr) != 0) {
    throw input_error(source, "cannot read the voxel data: " + teem_error());
  }
  image.labels = copy_nrrd_labels(*nrrd, voxels, source);
  take_placement(*nrrd, axes, image, source);
  read_segment_names(*nrrd, image, source);
  return image;
}

}  // namespace organsim::image_io
