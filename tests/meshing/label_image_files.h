#pragma once
// Labelled test images written byte by byte here (not by the libraries the
// readers use): NIfTI-1, NRRD (attached or detached data) and INR, each with
// a known placement, so that the readers and VTK's own readers can be checked
// against what was meant.
#include <zlib.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace organsim::testing {

struct TestVolume {
  std::array<int, 3> size{};
  std::vector<uint8_t> labels;  // i fastest
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: steps of i, j, k (mm)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();    // centre of voxel (0, 0, 0) (mm)
  uint8_t& at(int i, int j, int k) { return labels[static_cast<size_t>(i + size[0] * (j + size[1] * k))]; }
};

// An nx x ny x nz volume of label 0.
inline TestVolume empty_volume(int nx, int ny, int nz) {
  TestVolume v;
  v.size = {nx, ny, nz};
  v.labels.assign(static_cast<size_t>(nx) * ny * nz, 0);
  return v;
}

template <class T>
void put(std::string& bytes, size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

inline void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  if (path.extension() == ".gz") {
    gzFile f = gzopen(path.c_str(), "wb");
    gzwrite(f, bytes.data(), static_cast<unsigned>(bytes.size()));
    gzclose(f);
  } else {
    std::ofstream(path, std::ios::binary) << bytes;
  }
}

// NIfTI-1 single file (.nii or .nii.gz), uint8 labels, placement in the sform
// (sform_code 1), units: 2 = mm, 0 = none. `dims` overrides dim[0..7] (for
// 2D/4D tests); `data_bytes` < the data's size truncates the file.
struct NiftiOptions {
  int16_t units = 2;
  int16_t datatype = 2;  // uint8 (16: float32)
  std::array<int16_t, 8> dims{};  // all 0: 3D from the volume
  size_t keep_bytes = SIZE_MAX;   // truncate the whole file to this
};
inline void write_nifti(const std::filesystem::path& path, const TestVolume& v, const NiftiOptions& o = {}) {
  std::string header(352, '\0');
  put<int32_t>(header, 0, 348);
  std::array<int16_t, 8> dim = o.dims;
  if (dim[0] == 0) dim = {3, int16_t(v.size[0]), int16_t(v.size[1]), int16_t(v.size[2]), 1, 1, 1, 1};
  for (int d = 0; d < 8; ++d) put<int16_t>(header, 40 + 2 * d, dim[d]);
  const int bytes_per = o.datatype == 16 ? 4 : 1;
  put<int16_t>(header, 70, o.datatype);
  put<int16_t>(header, 72, int16_t(8 * bytes_per));
  put<float>(header, 76, 1.0f);
  for (int c = 0; c < 3; ++c) put<float>(header, 80 + 4 * c, float(v.axes.col(c).norm()));
  put<float>(header, 108, 352.0f);  // vox_offset
  put<float>(header, 112, 1.0f);    // scl_slope
  header[123] = static_cast<char>(o.units);
  put<int16_t>(header, 254, 1);  // sform_code: scanner anatomical
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) put<float>(header, 280 + 16 * r + 4 * c, float(v.axes(r, c)));
    put<float>(header, 280 + 16 * r + 12, float(v.origin[r]));
  }
  std::memcpy(header.data() + 344, "n+1\0", 4);
  std::string bytes = header;
  for (uint8_t l : v.labels) {
    if (bytes_per == 4) {
      const float f = l;
      bytes.append(reinterpret_cast<const char*>(&f), 4);
    } else {
      bytes.push_back(static_cast<char>(l));
    }
  }
  if (o.keep_bytes < bytes.size()) bytes.resize(o.keep_bytes);
  write_bytes(path, bytes);
}

inline std::string format_vector(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s.precision(17);
  s << "(" << v.x() << "," << v.y() << "," << v.z() << ")";
  return s.str();
}

// NRRD, uint8 raw data, in `space` (e.g. "left-posterior-superior") with the
// volume's axes and origin given in that space, units mm. `detached`: an
// .nhdr with its data in a .raw beside it. `extra` lines go in the header.
inline void write_nrrd(const std::filesystem::path& path, const TestVolume& v, const std::string& space,
                       bool detached = false, const std::string& extra = "", const std::string& sizes = "",
                       size_t keep_data_bytes = SIZE_MAX) {
  // `sizes` given: a 4D file whose first axis is a list (3D Slicer's layers).
  const bool layers = !sizes.empty();
  std::ostringstream h;
  h << "NRRD0004\n# written by organsim's tests\ntype: uint8\n";
  h << "dimension: " << (layers ? 4 : 3) << "\nspace: " << space << "\n";
  h << "sizes: " << (layers ? sizes : std::to_string(v.size[0]) + " " + std::to_string(v.size[1]) + " " + std::to_string(v.size[2])) << "\n";
  h << "space directions: " << (layers ? "none " : "") << format_vector(v.axes.col(0)) << " " << format_vector(v.axes.col(1))
    << " " << format_vector(v.axes.col(2)) << "\n";
  h << "kinds: " << (layers ? "list " : "") << "domain domain domain\nendian: little\nencoding: raw\n";
  h << "space units: \"mm\" \"mm\" \"mm\"\n";
  h << "space origin: " << format_vector(v.origin) << "\n" << extra;
  std::string data(v.labels.begin(), v.labels.end());
  if (keep_data_bytes < data.size()) data.resize(keep_data_bytes);
  if (detached) {
    const auto raw = std::filesystem::path(path).replace_extension(".raw");
    h << "data file: " << raw.filename().string() << "\n";
    write_bytes(path, h.str());
    write_bytes(raw, data);
  } else {
    h << "\n";
    write_bytes(path, h.str() + data);
  }
}

// INR (CGAL's format): a 256-byte header block, uint8 data, spacing only.
inline void write_inr(const std::filesystem::path& path, const TestVolume& v) {
  std::ostringstream h;
  h << "#INRIMAGE-4#{\nXDIM=" << v.size[0] << "\nYDIM=" << v.size[1] << "\nZDIM=" << v.size[2]
    << "\nVDIM=1\nTYPE=unsigned fixed\nPIXSIZE=8 bits\nCPU=decm\nVX=" << v.axes(0, 0) << "\nVY=" << v.axes(1, 1)
    << "\nVZ=" << v.axes(2, 2) << "\n";
  std::string header = h.str();
  header += std::string(256 - 4 - header.size(), '\n') + "##}\n";
  write_bytes(path, header + std::string(v.labels.begin(), v.labels.end()));
}

}  // namespace organsim::testing
