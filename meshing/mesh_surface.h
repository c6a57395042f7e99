#pragma once
// Tetrahedralisation of closed surfaces with CGAL Mesh_3 (the only CGAL user).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh/tet_mesh.h"

namespace organsim {

struct MeshOptions {
  std::optional<int32_t> target_points;  // aim for this many points (+-10 %)
  std::optional<double> cell_size;       // max tet circumradius h, m
  std::optional<double> facet_distance;  // max surface approximation error, m (default 0.1 h)
  bool exude = true;                     // sliver exudation (slower, much better dihedral angles)
};

struct MeshQuality {
  double min_dihedral_deg = 0, max_dihedral_deg = 0;
  double max_radius_edge_ratio = 0;
  double min_tet_volume = 0;  // m^3
};

struct MeshReport {
  int32_t points = 0, springs = 0, tets = 0, boundary_triangles = 0;
  MeshQuality quality;
  std::vector<int32_t> valence_histogram;  // [k] = points with k springs
  double seconds = 0;
  std::vector<std::string> notes;          // e.g. "surface was inward oriented: reversed"
};

// Validates the surface (triangle mesh, faces > 0, closed, not
// self-intersecting, bounds a volume; inward orientation is fixed and noted)
// and meshes it. Throws Error(Input) naming `source`.
TetMesh mesh_surface(const TriangleMesh& surface, const MeshOptions& options,
                     const std::string& source, MeshReport* report = nullptr);

// read_surface + mesh_surface.
TetMesh mesh_surface_file(const std::filesystem::path& path, const MeshOptions& options,
                          MeshReport* report = nullptr);

// Counts and quality of any tet mesh (used for meshes read from file too).
MeshReport describe_tet_mesh(const TetMesh& mesh);

}  // namespace organsim
