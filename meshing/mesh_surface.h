#pragma once
// Tetrahedralisation of closed surfaces with CGAL Mesh_3 (the only CGAL user).
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh/mesh_stats.h"  // MeshQuality, MeshReport, describe_tet_mesh
#include "core/mesh/tet_mesh.h"

namespace organsim {

struct MeshOptions {
  std::optional<int32_t> target_points;  // aim for this many points (+-10 %)
  std::optional<double> cell_size;       // max tet circumradius h, m
  std::optional<double> facet_distance;  // max surface approximation error, m (default 0.1 h)
  bool exude = true;                     // sliver exudation (1.3-3x slower, much better dihedral angles)
  // Told the stage meshing has reached ("meshing at cell size 0.004 m"), for
  // a progress line; meshing a large target can take minutes.
  std::function<void(const std::string&)> on_stage;
};

// Validates the surface (triangle mesh, faces > 0, closed, not
// self-intersecting, bounds a volume; inward orientation is fixed and noted)
// and meshes it. Throws Error(Input) naming `source`.
TetMesh mesh_surface(const TriangleMesh& surface, const MeshOptions& options,
                     const std::string& source, MeshReport* report = nullptr);

// read_surface + mesh_surface.
TetMesh mesh_surface_file(const std::filesystem::path& path, const MeshOptions& options,
                          MeshReport* report = nullptr);

// describe_tet_mesh (counts and quality of any tet mesh) is declared in
// core/mesh/mesh_stats.h, so meshes read from file are described without CGAL.

}  // namespace organsim
