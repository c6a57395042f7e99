// NIfTI-1 labelled volumes (.nii, .nii.gz) through Debian's libniftiio: the
// library parses the header and reads (and inflates, byte-swaps) the data;
// this file checks that it is a segmentation and takes its placement.
#include <nifti1_io.h>

#include <memory>
#include <string>

#include "core/util/error.h"
#include "meshing/gzip_stream.h"
#include "meshing/label_image.h"

namespace organsim::image_io {

namespace {

struct NiftiFree {
  void operator()(nifti_image* image) const { nifti_image_free(image); }
};

std::vector<int32_t> copy_nifti_labels(const nifti_image& nim, const std::string& source) {
  const auto n = static_cast<int64_t>(nim.nvox);
  switch (nim.datatype) {
    case DT_UINT8: return copy_labels<uint8_t>(nim.data, n, source);
    case DT_INT8: return copy_labels<int8_t>(nim.data, n, source);
    case DT_UINT16: return copy_labels<uint16_t>(nim.data, n, source);
    case DT_INT16: return copy_labels<int16_t>(nim.data, n, source);
    case DT_UINT32: return copy_labels<uint32_t>(nim.data, n, source);
    case DT_INT32: return copy_labels<int32_t>(nim.data, n, source);
    case DT_UINT64: return copy_labels<uint64_t>(nim.data, n, source);
    case DT_INT64: return copy_labels<int64_t>(nim.data, n, source);
    default: break;
  }
  throw input_error(source, std::string("voxels of type ") + nifti_datatype_string(nim.datatype) +
                                ": a segmentation stores integer labels (uint8, int16, ..., int64)");
}

}  // namespace

LabelImage read_nifti(const std::filesystem::path& path, const std::string& source) {
  nifti_set_debug_level(0);  // errors are ours to report, naming the file
  // The header first: nothing is allocated for the data until it is checked.
  std::unique_ptr<nifti_image, NiftiFree> nim(nifti_image_read(path.c_str(), 0));
  if (!nim) {
    throw input_error(source, "not a readable NIfTI-1 file (bad or truncated header, or NIfTI-2, which is not supported)");
  }
  const int ndim = nim->dim[0];
  if (ndim < 3) {
    throw input_error(source, std::to_string(ndim) + "D image: a segmentation for meshing is a 3D volume");
  }
  int64_t volumes = 1;
  for (int d = 4; d <= ndim && d < 8; ++d) volumes *= std::max(1, static_cast<int>(nim->dim[d]));
  if (volumes != 1) {
    throw input_error(source, std::to_string(ndim) + "D image with " + std::to_string(volumes) +
                                  " volumes: a segmentation for meshing is one 3D volume of labels");
  }
  if (nim->scl_slope != 0 && (nim->scl_slope != 1 || nim->scl_inter != 0)) {
    throw input_error(source, "the voxel values are scaled (scl_slope " + std::to_string(nim->scl_slope) + ", scl_inter " +
                                  std::to_string(nim->scl_inter) + "): a segmentation stores integer labels as they are");
  }
  LabelImage image;
  image.size = {nim->nx, nim->ny, nim->nz};
  for (int64_t s : image.size) {
    if (s <= 0) throw input_error(source, "the header gives a dimension of " + std::to_string(s) + " voxels");
  }
  // Before loading: the data must fit in what the file holds.
  std::error_code ec;
  const auto file_bytes = static_cast<int64_t>(std::filesystem::file_size(path, ec));
  if (ec) throw input_error(source, "cannot read its size: " + ec.message());
  const bool compressed = nifti_is_gzfile(path.c_str()) != 0;
  // vox_offset is a float in the header: a negative or huge one would make
  // the bound below meaningless (a 353-byte file claiming 455 M voxels at
  // vox_offset -4e37 passed it and made the library allocate them).
  if (nim->iname_offset < 0 || (!compressed && nim->iname_offset > file_bytes)) {
    throw input_error(source, "the header's vox_offset (" + std::to_string(nim->iname_offset) +
                                  ") lies outside the file's " + std::to_string(file_bytes) + " bytes");
  }
  const int64_t offset = compressed ? 0 : static_cast<int64_t>(nim->iname_offset);
  check_data_size(image.voxel_count(), nim->nbyper, max_data_bytes(file_bytes - offset, compressed), source);
  if (compressed) {
    // libniftiio zero-fills what a short stream lacks: it is read whole first.
    require_whole_gzip(path, source, 0, nim->iname_offset + image.voxel_count() * nim->nbyper,
                       "vox_offset " + std::to_string(nim->iname_offset) + " + " + std::to_string(image.voxel_count()) +
                           " voxels of " + std::to_string(nim->nbyper) + " bytes");
  }
  if (nifti_image_load(nim.get()) != 0 || nim->data == nullptr) {
    throw input_error(source, "the voxel data is shorter than the header says (" + std::to_string(image.voxel_count()) +
                                  " voxels of " + std::to_string(nim->nbyper) + " bytes)");
  }
  image.labels = copy_nifti_labels(*nim, source);

  // Placement: sform when it is set (the transform to a standard or aligned
  // space), else qform (the scanner's), else the voxel spacing alone.
  const mat44* m = nullptr;
  if (nim->sform_code > 0) {
    m = &nim->sto_xyz;
    image.notes.push_back("placement from the sform (code " + std::to_string(nim->sform_code) + ")");
  } else if (nim->qform_code > 0) {
    m = &nim->qto_xyz;
    image.notes.push_back("placement from the qform (code " + std::to_string(nim->qform_code) + ")");
  }
  if (m != nullptr) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) image.axes(r, c) = m->m[r][c];
      image.origin[r] = m->m[r][3];
    }
  } else {
    image.axes = Eigen::Vector3d(nim->dx, nim->dy, nim->dz).asDiagonal();
    image.notes.push_back("no qform or sform: voxel spacing only, voxel (0, 0, 0) at the origin");
  }
  switch (nim->xyz_units) {
    case NIFTI_UNITS_METER: image.metres_per_unit = 1.0; image.unit_name = "m"; break;
    case NIFTI_UNITS_MM: image.metres_per_unit = 1e-3; image.unit_name = "mm"; break;
    case NIFTI_UNITS_MICRON: image.metres_per_unit = 1e-6; image.unit_name = "micron"; break;
    default: break;
  }
  return image;
}

}  // namespace organsim::image_io
