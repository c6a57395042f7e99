// Surface -> tet mesh: validation, the cell-size choice (or the search for
// a target point count) and the report. CGAL stays behind mesh_3.h and
// surface_check.h.
#include "meshing/mesh_surface.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/mesh/mesh_io.h"
#include "core/util/error.h"
#include "core/util/format.h"
#include "meshing/cell_size_search.h"
#include "meshing/mesh_3.h"
#include "meshing/meshed_check.h"
#include "meshing/surface_check.h"

namespace organsim {

namespace {

double bounding_box_diagonal(const TriangleMesh& surface) {
  Vec3 lo = surface.points.front(), hi = lo;
  for (const Vec3& p : surface.points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

// Below this fraction of the bounding-box diagonal, the facet distance asks
// for a surface refinement that does not end in reasonable time.
constexpr double kMinRelativeFacetDistance = 1e-6;

void check_point_estimate(double volume, double h) {
  const double estimate = volume / (h * h * h);
  if (!(estimate <= kMaxEstimatedPoints)) {
    throw Error(ErrorKind::Usage, "cell size " + format_number(h) + " m would make about " + format_number(estimate) +
                                      " points in this surface (" + format_number(volume) +
                                      " m^3); expected at most " + format_number(kMaxEstimatedPoints) +
                                      ": give a larger cell size");
  }
}

void stage(const MeshOptions& options, const std::string& what) {
  if (options.on_stage) options.on_stage(what);
}

}  // namespace

TetMesh mesh_surface(const TriangleMesh& surface, const MeshOptions& options, const std::string& source,
                     MeshReport* report) {
  const auto start = std::chrono::steady_clock::now();
  if (options.target_points && options.cell_size) {
    throw Error(ErrorKind::Usage, "give either a target point count or a cell size, not both");
  }
  if (options.target_points && *options.target_points < 4) {
    throw Error(ErrorKind::Usage, "target points must be at least 4, got " + std::to_string(*options.target_points));
  }
  if (options.cell_size && !(*options.cell_size > 0)) {
    throw Error(ErrorKind::Usage, "cell size must be positive (metres), got " + format_number(*options.cell_size));
  }
  if (options.facet_distance && !(*options.facet_distance > 0)) {
    throw Error(ErrorKind::Usage, "facet distance must be positive (metres), got " + format_number(*options.facet_distance));
  }

  std::vector<std::string> notes;
  stage(options, "checking the surface");
  const TriangleMesh checked = check_surface(surface, source, notes);
  const double size = bounding_box_diagonal(checked);
  if (options.cell_size) check_point_estimate(surface_volume(checked), *options.cell_size);
  if (options.facet_distance && *options.facet_distance < kMinRelativeFacetDistance * size) {
    throw Error(ErrorKind::Usage, "facet distance " + format_number(*options.facet_distance) + " m is below " +
                                      format_number(kMinRelativeFacetDistance) + " of the surface's size (" +
                                      format_number(size) + " m): meshing would not finish");
  }
  const Mesh3Domain domain(checked);
  double h = 0;
  if (options.cell_size) {
    h = *options.cell_size;
  } else if (options.target_points) {
    const auto points_at = [&](double cell) {
      return static_cast<int32_t>(domain.mesh({cell, options.facet_distance.value_or(0.1 * cell), /*exude=*/false}).points.size());
    };
    h = search_cell_size(points_at, surface_volume(checked), *options.target_points,
                         [&](const std::string& what) { stage(options, what); }, source, notes);
  } else {
    h = size / 20.0;  // default: see docs/meshing.md
    notes.push_back("no --cell-size or --target-points: cell size " + format_number(h) +
                    " m (bounding-box diagonal / 20)");
  }
  stage(options, "meshing at cell size " + format_number(h) + " m" + (options.exude ? ", then sliver exudation" : ""));
  const TetMesh mesh = domain.mesh({h, options.facet_distance.value_or(0.1 * h), options.exude});
  if (mesh.tets.empty()) {
    throw input_error(source, "meshing produced no tetrahedra at cell size " + format_number(h) +
                                  " m; is the surface much smaller than the cell size?");
  }
  check_meshed(mesh, source);
  if (report != nullptr) {
    *report = describe_tet_mesh(mesh);
    report->notes = notes;
    report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return mesh;
}

TetMesh mesh_surface_file(const std::filesystem::path& path, const MeshOptions& options, MeshReport* report) {
  return mesh_surface(read_surface(path), options, path.string(), report);
}

}  // namespace organsim
