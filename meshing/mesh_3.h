#pragma once
// The single translation unit that instantiates CGAL Mesh_3 (~40 s, ~4 GB to
// compile), behind a small interface so nothing else includes it.
#include <memory>

#include "core/mesh/tet_mesh.h"

namespace organsim {

struct Mesh3Criteria {
  double cell_size = 0;       // max tet circumradius and max facet size h, m
  double facet_distance = 0;  // max distance of facet circumcentres to the surface, m
  bool exude = true;          // sliver exudation after refinement
};

// A polyhedral domain built once from a checked (closed, outward, not
// self-intersecting) surface and meshed as often as needed, e.g. while
// searching for a cell size. Meshing is sequential and seeded identically
// each time, so the same criteria give the same mesh.
class Mesh3Domain {
 public:
  explicit Mesh3Domain(const TriangleMesh& checked_surface);
  ~Mesh3Domain();
  Mesh3Domain(const Mesh3Domain&) = delete;
  Mesh3Domain& operator=(const Mesh3Domain&) = delete;

  // Positively oriented tets; points are the vertices the tets use.
  TetMesh mesh(const Mesh3Criteria& criteria) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace organsim
