#pragma once
// The translation unit that instantiates CGAL Mesh_3 on a labelled image
// (Labeled_mesh_domain_3; ~40 s, ~4 GB to compile), behind a small interface
// so nothing else includes it. Works in the image's voxel frame; placing the
// mesh in the world is mesh_image.cpp's job.
#include <array>
#include <map>
#include <memory>
#include <vector>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// Labels on a regular grid, voxel (i, j, k) centred at (i sx, j sy, k sz).
struct LabelGrid {
  std::array<int64_t, 3> size{};
  const std::vector<int32_t>* labels = nullptr;  // i fastest; 0 is outside
  Vec3 spacing = Vec3::Ones();                   // sx, sy, sz (> 0)
};

struct Mesh3ImageCriteria {
  double cell_size = 0;                     // max tet circumradius and facet size, grid units
  std::map<int32_t, double> label_cell_size;  // per label, overriding cell_size inside it
  double facet_distance = 0;                // max distance of facets to the label interfaces, grid units
  bool exude = true;
};

// The grid padded by one voxel of label 0 on every side, so that labels on
// the image's border get a closed boundary, and the labelled domain built
// once; meshed as often as needed (sequential, seeded identically each time:
// the same criteria give the same mesh).
class Mesh3ImageDomain {
 public:
  explicit Mesh3ImageDomain(const LabelGrid& grid);
  ~Mesh3ImageDomain();
  Mesh3ImageDomain(const Mesh3ImageDomain&) = delete;
  Mesh3ImageDomain& operator=(const Mesh3ImageDomain&) = delete;

  // Positively oriented tets in grid units, each with its label in
  // TetMesh::labels; neighbouring labels share the interface's points.
  TetMesh mesh(const Mesh3ImageCriteria& criteria) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace organsim
