// Labelled image -> labelled tet mesh (see mesh_image.h).
#include "meshing/mesh_image.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/util/error.h"
#include "core/util/format.h"
#include "meshing/cell_size_search.h"
#include "meshing/mesh_3_image.h"
#include "meshing/meshed_check.h"

namespace organsim {

namespace {

void stage(const ImageMeshOptions& options, const std::string& what) {
  if (options.on_stage) options.on_stage(what);
}

void check_positive(std::optional<double> value, const std::string& what) {
  if (value && !(*value > 0 && std::isfinite(*value))) {
    throw Error(ErrorKind::Usage, what + " must be a positive number of metres, got " + format_number(*value));
  }
}

// Shrinks the image to the box of its non-zero voxels (a CT segmentation is
// mostly outside); the origin moves with it so nothing changes place.
void crop_to_labels(LabelImage& image) {
  std::array<int64_t, 3> lo{image.size}, hi{-1, -1, -1};
  for (int64_t k = 0; k < image.size[2]; ++k) {
    for (int64_t j = 0; j < image.size[1]; ++j) {
      for (int64_t i = 0; i < image.size[0]; ++i) {
        if (image.at(i, j, k) == 0) continue;
        const int64_t idx[3] = {i, j, k};
        for (int c = 0; c < 3; ++c) {
          lo[c] = std::min(lo[c], idx[c]);
          hi[c] = std::max(hi[c], idx[c]);
        }
      }
    }
  }
  const std::array<int64_t, 3> size{hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
  if (size == image.size) return;
  std::vector<int32_t> labels(static_cast<size_t>(size[0] * size[1] * size[2]));
  for (int64_t k = 0; k < size[2]; ++k) {
    for (int64_t j = 0; j < size[1]; ++j) {
      for (int64_t i = 0; i < size[0]; ++i) {
        labels[static_cast<size_t>(i + size[0] * (j + size[1] * k))] = image.at(i + lo[0], j + lo[1], k + lo[2]);
      }
    }
  }
  image.origin += image.axes * Vec3(double(lo[0]), double(lo[1]), double(lo[2]));
  image.size = size;
  image.labels = std::move(labels);
}

}  // namespace

TetMesh mesh_label_image(LabelImage image, const ImageMeshOptions& options, const std::string& source,
                         MeshReport* report) {
  const auto start = std::chrono::steady_clock::now();
  // A target count sizes every label without a size of its own; labels given
  // one (a tumour finer than its organ) keep it.
  if (options.target_points && options.cell_size) {
    throw Error(ErrorKind::Usage, "give either a target point count or a cell size for every label, not both "
                                  "(per-label cell sizes may go with a target)");
  }
  if (options.target_points && *options.target_points < 4) {
    throw Error(ErrorKind::Usage, "target points must be at least 4, got " + std::to_string(*options.target_points));
  }
  check_positive(options.cell_size, "cell size");
  check_positive(options.facet_distance, "facet distance");
  for (const auto& [label, h] : options.label_cell_size) check_positive(h, "cell size of label " + std::to_string(label));

  stage(options, "reading the labels");
  apply_image_units(image, options.metres_per_unit, source);
  select_labels(image, options.labels, source);
  crop_to_labels(image);
  std::vector<std::string> notes = image.notes;
  for (const auto& [label, h] : options.label_cell_size) {
    if (std::find(image.labels.begin(), image.labels.end(), label) == image.labels.end()) {
      throw Error(ErrorKind::Usage, source + ": --cell-size for label " + std::to_string(label) +
                                        ", which has no voxel in the meshed labels");
    }
  }

  // The mesher works in a frame where the smallest voxel spacing is 1.
  const Vec3 spacing(image.axes.col(0).norm(), image.axes.col(1).norm(), image.axes.col(2).norm());
  const double unit = spacing.minCoeff();
  const std::map<int32_t, int64_t> counts = label_voxel_counts(image);
  const double voxel = voxel_volume(image);
  double labelled_volume = 0;
  for (const auto& [label, n] : counts) labelled_volume += label != 0 ? double(n) * voxel : 0.0;
  const double diagonal = Vec3(spacing.x() * double(image.size[0]), spacing.y() * double(image.size[1]),
                               spacing.z() * double(image.size[2])).norm();

  Mesh3ImageCriteria criteria;
  criteria.exude = options.exude;
  for (const auto& [label, h] : options.label_cell_size) criteria.label_cell_size[label] = h / unit;
  const auto smallest_cell = [&](double h) {
    double smallest = h;
    for (const auto& [label, hl] : options.label_cell_size) smallest = std::min(smallest, hl);
    return smallest;
  };
  // The interfaces follow voxel steps: a facet distance below half a voxel
  // would chase the staircase. Default: 0.1 h (as for surfaces), at least half a voxel.
  const auto facet_distance = [&](double h) {
    return options.facet_distance.value_or(std::max(0.1 * smallest_cell(h), 0.5 * unit));
  };
  const auto check_estimate = [&](double h) {
    double estimate = 0;
    for (const auto& [label, n] : counts) {
      if (label == 0) continue;
      const auto it = options.label_cell_size.find(label);
      const double hl = it == options.label_cell_size.end() ? h : it->second;
      estimate += double(n) * voxel / (hl * hl * hl);
    }
    if (!(estimate <= kMaxEstimatedPoints)) {
      throw Error(ErrorKind::Usage, "these cell sizes would make about " + format_number(estimate) +
                                        " points in the labels' " + format_number(labelled_volume) +
                                        " m^3; expected at most " + format_number(kMaxEstimatedPoints) +
                                        ": give larger cell sizes");
    }
  };

  const LabelGrid grid{image.size, &image.labels, spacing / unit};
  stage(options, "building the labelled domain");
  const Mesh3ImageDomain domain(grid);
  const auto mesh_at = [&](double h, bool exude) {
    Mesh3ImageCriteria c = criteria;
    c.cell_size = h / unit;
    c.facet_distance = facet_distance(h) / unit;
    c.exude = exude;
    return domain.mesh(c);
  };
  double h = 0;
  if (options.cell_size) {
    h = *options.cell_size;
  } else if (options.target_points) {
    // The search varies the cell size of the labels without their own; its
    // first guess spreads the target over their volume.
    double free_volume = 0;
    for (const auto& [label, n] : counts) {
      if (label != 0 && !options.label_cell_size.count(label)) free_volume += double(n) * voxel;
    }
    if (!(free_volume > 0)) {
      throw Error(ErrorKind::Usage, source + ": every meshed label has its own --cell-size, so --target-points "
                                             "has no cell size left to choose; leave one label without a size");
    }
    const auto points_at = [&](double cell) { return static_cast<int32_t>(mesh_at(cell, false).points.size()); };
    h = search_cell_size(points_at, free_volume, *options.target_points,
                         [&](const std::string& what) { stage(options, what); }, source, notes);
  } else {
    h = diagonal / 20.0;
    notes.push_back("no --cell-size or --target-points: cell size " + format_number(h) +
                    " m (labelled region's bounding-box diagonal / 20)");
  }
  check_estimate(h);
  stage(options, "meshing at cell size " + format_number(h) + " m" + (options.exude ? ", then sliver exudation" : ""));
  TetMesh mesh = mesh_at(h, options.exude);
  if (mesh.tets.empty()) {
    throw input_error(source, "meshing produced no tetrahedra at cell size " + format_number(h) +
                                  " m; are the labels much smaller than the cell size?");
  }

  // Into the image's physical frame: grid coordinate x_c = index_c * spacing_c / unit.
  const Eigen::Matrix3d to_world = image.axes * (spacing / unit).cwiseInverse().asDiagonal();
  for (Vec3& p : mesh.points) p = image.origin + to_world * p;
  if (to_world.determinant() < 0) {
    for (Tet& t : mesh.tets) std::swap(t[2], t[3]);  // a mirroring placement (e.g. LPS voxel axes)
  }
  check_meshed(mesh, source);

  if (report != nullptr) {
    *report = describe_tet_mesh(mesh);
    report->notes = notes;
    for (LabelStats& l : report->labels) {
      const auto it = counts.find(l.label);
      l.image_volume = it == counts.end() ? 0.0 : double(it->second) * voxel;
      const auto name = image.names.find(l.label);
      if (name != image.names.end()) l.name = name->second;
    }
    for (const auto& [label, n] : counts) {
      if (label == 0) continue;
      const bool meshed = std::any_of(report->labels.begin(), report->labels.end(),
                                      [&](const LabelStats& l) { return l.label == label; });
      if (!meshed) {
        LabelStats lost;
        lost.label = label;
        lost.image_volume = double(n) * voxel;
        const auto name = image.names.find(label);
        if (name != image.names.end()) lost.name = name->second;
        report->labels.push_back(lost);
      }
    }
    std::sort(report->labels.begin(), report->labels.end(),
              [](const LabelStats& a, const LabelStats& b) { return a.label < b.label; });
    for (const LabelStats& l : report->labels) {
      const double off = l.relative_difference().value_or(0);
      if (off > kLabelVolumeWarning) {
        report->warnings.push_back("label " + std::to_string(l.label) + ": mesh volume " + format_number(l.mesh_volume) +
                                   " m^3 is " + format_number(100 * off, "%.1f") + " % off its image volume " +
                                   format_number(*l.image_volume) + " m^3" +
                                   (l.tets == 0 ? " (no tets: thinner than the cell size?)"
                                                : " (parts thinner than a voxel or the cell size?)"));
      }
    }
    report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return mesh;
}

TetMesh mesh_image_file(const std::filesystem::path& path, const ImageMeshOptions& options, MeshReport* report) {
  return mesh_label_image(read_label_image(path), options, path.string(), report);
}

}  // namespace organsim
