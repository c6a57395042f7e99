#pragma once
// Labelled image (segmentation) -> one conforming tet mesh whose tets carry
// their label: units, label selection, cropping to the labelled voxels, the
// cell sizes (or the search for a target point count), placement in the
// image's physical frame, and the report comparing each label's volume in
// the image and in the mesh. CGAL stays behind mesh_3_image.h.
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh/mesh_stats.h"
#include "meshing/label_image.h"

namespace organsim {

struct ImageMeshOptions {
  std::optional<int32_t> target_points;     // aim for this many points (+-10 %)
  std::optional<double> cell_size;          // max tet circumradius h, m, for every label not below
  std::map<int32_t, double> label_cell_size;  // per label, m (a tumour finer than its organ)
  std::optional<double> facet_distance;     // max interface approximation error, m
  bool exude = true;
  std::vector<int32_t> labels;              // keep only these labels (empty: every label > 0)
  std::optional<double> metres_per_unit;    // for a header that names no length unit (--units, --scale)
  std::function<void(const std::string&)> on_stage;
};

// A label's mesh volume differing from its image volume by more than this
// fraction is a warning in the report (a structure thinner than a voxel or
// the cell size, lost or thickened).
constexpr double kLabelVolumeWarning = 0.05;

// Meshes `image` as read by read_label_image (units not yet applied).
// Throws Error(Input) naming `source` (no voxel of the labels, meshing gave
// nothing) or Error(Usage) (bad sizes, no unit).
TetMesh mesh_label_image(LabelImage image, const ImageMeshOptions& options, const std::string& source,
                         MeshReport* report = nullptr);

// read_label_image + mesh_label_image.
TetMesh mesh_image_file(const std::filesystem::path& path, const ImageMeshOptions& options,
                        MeshReport* report = nullptr);

}  // namespace organsim
