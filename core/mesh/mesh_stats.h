#pragma once
// Counts and quality of tet meshes, without CGAL, so meshes read from file
// are described exactly like meshes made by `organsim mesh`.
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh/tet_mesh.h"

namespace organsim {

struct MeshQuality {
  double min_dihedral_deg = 0, max_dihedral_deg = 0;
  double max_radius_edge_ratio = 0;  // circumradius / shortest edge (regular tet: 0.612)
  double min_tet_volume = 0;         // m^3
};

// One subdomain label of a labelled mesh: its tets and volume, and where the
// mesh came from an image, the volume of its voxels (so that a structure
// thinner than the voxels or the cell size shows as a difference).
struct LabelStats {
  int32_t label = 0;
  std::string name;                    // a segment's name, when the image gives one
  int32_t tets = 0;
  double mesh_volume = 0;              // m^3
  std::optional<double> image_volume;  // m^3
  // |mesh - image| / image, or nullopt without an image volume.
  std::optional<double> relative_difference() const;
};

struct MeshReport {
  int32_t points = 0, springs = 0, tets = 0, boundary_triangles = 0;
  MeshQuality quality;
  std::vector<int32_t> valence_histogram;  // [k] = points with k springs
  double seconds = 0;                      // wall time of the meshing (0 when read from file)
  std::vector<std::string> notes;          // e.g. "surface was inward oriented: reversed"
  std::vector<LabelStats> labels;          // ascending by label; empty for an unlabelled mesh
  std::vector<std::string> warnings;       // e.g. a label's mesh volume 8 % off its image volume
};

// Counts (springs = unique tet edges; boundary triangles = faces of exactly
// one tet), quality and the springs-per-point histogram. The mesh must be
// valid (validate_tet_mesh: indices in range, positive volumes).
MeshReport describe_tet_mesh(const TetMesh& mesh);

// Tets and volume per label of a labelled mesh (empty when unlabelled),
// ascending by label; image_volume is left empty.
std::vector<LabelStats> label_stats(const TetMesh& mesh);

// Unique tet edges (a < b), sorted.
std::vector<Edge> unique_edges(const TetMesh& mesh);

// Faces owned by exactly one tet, oriented outward (counter-clockwise seen
// from outside) for positively oriented tets.
std::vector<Tri> boundary_triangles(const TetMesh& mesh);

// Sum of the tets' signed volumes, m^3.
double tet_mesh_volume(const TetMesh& mesh);

// Volume enclosed by a closed surface (divergence theorem), m^3; negative
// when the faces are oriented inward.
double surface_volume(const TriangleMesh& surface);

// Human-readable report: counts, quality, the histogram as text bars, time.
std::string format_mesh_report(const MeshReport& report);
// The same as JSON (keys: points, springs, tets, boundary_triangles, quality{...},
// springs_per_point{mean, max, histogram}, seconds, notes).
nlohmann::json mesh_report_json(const MeshReport& report);

}  // namespace organsim
