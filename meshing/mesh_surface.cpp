// Surface -> tet mesh: validation, the cell-size choice (or the search for
// a target point count) and the report. CGAL stays behind mesh_3.h and
// surface_check.h.
#include "meshing/mesh_surface.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "core/mesh/mesh_io.h"
#include "core/util/error.h"
#include "meshing/mesh_3.h"
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

std::string format_number(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

// The point count N of a Mesh_3 mesh falls roughly like h^-3 with the cell
// size h (more slowly for coarse meshes, where surface points dominate).
// Start from N ~ kPointsPerVolume * V / h^3, then secant steps on
// (log h, log N). Deterministic: the same surface and target give the same h.
constexpr double kPointsPerVolume = 1.0;  // first guess only; corrected by the iteration
constexpr double kAcceptTolerance = 0.03;  // stop when within 3 % (the promise is 10 %)
constexpr int kMaxTries = 10;

// Absurd cell sizes are refused before Mesh_3 runs for hours: a surface
// enclosing V m^3 meshed at cell size h gets roughly V / h^3 points.
constexpr double kMaxEstimatedPoints = 5e7;
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

struct Try {
  double h;
  int32_t points;
};

double search_cell_size(const Mesh3Domain& domain, double volume, int32_t target, const MeshOptions& options,
                        const std::string& source, std::vector<std::string>& notes) {
  const auto facet_distance = [&](double h) { return options.facet_distance.value_or(0.1 * h); };
  std::vector<Try> tries;
  double h = std::cbrt(kPointsPerVolume * volume / target);
  for (int i = 0; i < kMaxTries; ++i) {
    stage(options, "searching the cell size for " + std::to_string(target) + " points: try " + std::to_string(i + 1) +
                       " of at most " + std::to_string(kMaxTries) + ", cell size " + format_number(h) + " m");
    const TetMesh m = domain.mesh({h, facet_distance(h), /*exude=*/false});
    tries.push_back({h, static_cast<int32_t>(m.points.size())});
    const double error = std::log(static_cast<double>(tries.back().points) / target);
    if (std::abs(error) < std::log1p(kAcceptTolerance)) break;
    double slope = -3.0;
    if (tries.size() >= 2) {
      const Try& a = tries[tries.size() - 2];
      const Try& b = tries.back();
      if (a.h != b.h && a.points != b.points) {
        slope = (std::log(double(b.points)) - std::log(double(a.points))) / (std::log(b.h) - std::log(a.h));
      }
      slope = std::clamp(slope, -4.0, -1.0);
    }
    // Never jump by more than a factor 2 in one step.
    const double step = std::clamp(-error / slope, -std::log(2.0), std::log(2.0));
    h *= std::exp(step);
  }
  const Try best = *std::min_element(tries.begin(), tries.end(), [&](const Try& a, const Try& b) {
    return std::abs(std::log(double(a.points) / target)) < std::abs(std::log(double(b.points) / target));
  });
  std::ostringstream note;
  note << "target " << target << " points: cell size " << format_number(best.h) << " m after " << tries.size()
       << " tries (" << best.points << " points)";
  notes.push_back(note.str());
  if (std::abs(best.points - target) > 0.1 * target) {
    throw input_error(source, "cannot reach " + std::to_string(target) + " points within 10 %: closest was " +
                                      std::to_string(best.points) + " at cell size " + format_number(best.h) +
                                      " m; give --cell-size instead");
  }
  return best.h;
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
    h = search_cell_size(domain, surface_volume(checked), *options.target_points, options, source, notes);
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
  // Never hand on a mesh we would refuse to read back (zero or negative volumes).
  try {
    validate_tet_mesh(mesh, source);
  } catch (const Error& e) {
    throw Error(ErrorKind::Numerical, std::string("meshing gave a degenerate mesh, not used: ") + e.what() +
                                          "; try another cell size");
  }
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
