// Surface validation with CGAL's Polygon_mesh_processing (second CGAL TU; Mesh_3 is in mesh_3.cpp).
#include "meshing/surface_check.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <map>

#include "core/mesh/mesh_stats.h"
#include "core/mesh/surface_limits.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

// Why a face could not be added to a halfedge mesh: an edge used by more than
// two faces, or used twice in the same direction (faces flipped relative to
// their neighbours). Otherwise a vertex where two fans of faces touch.
std::string manifold_problem(const TriangleMesh& surface) {
  std::map<std::pair<int32_t, int32_t>, int> directed;
  for (const Tri& f : surface.faces) {
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  }
  size_t shared_by_more = 0, same_direction = 0;
  std::map<std::pair<int32_t, int32_t>, int> undirected;
  for (const auto& [edge, count] : directed) {
    if (count > 1) ++same_direction;
    undirected[{std::min(edge.first, edge.second), std::max(edge.first, edge.second)}] += count;
  }
  for (const auto& [edge, count] : undirected) {
    if (count > 2) ++shared_by_more;
  }
  if (shared_by_more > 0) {
    return "not a manifold surface: " + std::to_string(shared_by_more) +
           " edges are shared by more than two faces (expected a closed surface, each edge shared by exactly two faces)";
  }
  if (same_direction > 0) {
    return "faces are not consistently oriented: " + std::to_string(same_direction) +
           " edges are traversed twice in the same direction (make neighbouring faces agree, e.g. MeshLab's "
           "'Re-Orient all faces coherently')";
  }
  return "not a manifold surface: some vertex joins separate fans of faces (split it or remove the touching part)";
}

}  // namespace

TriangleMesh check_surface(const TriangleMesh& surface, const std::string& source, std::vector<std::string>& notes) {
  // Numbers and degenerate faces first: CGAL checks none of them.
  const double size = check_surface_limits(surface, source);

  // Only referenced vertices, so isolated points cannot confuse the checks or Mesh_3.
  TriangleMesh clean;
  std::vector<int32_t> new_index(surface.points.size(), -1);
  SurfaceMesh mesh;
  std::vector<SurfaceMesh::Vertex_index> vertices;
  for (const Tri& f : surface.faces) {
    Tri g{};
    for (int k = 0; k < 3; ++k) {
      int32_t& id = new_index[static_cast<size_t>(f[k])];
      if (id < 0) {
        id = static_cast<int32_t>(clean.points.size());
        const Vec3& p = surface.points[static_cast<size_t>(f[k])];
        clean.points.push_back(p);
        vertices.push_back(mesh.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z())));
      }
      g[k] = id;
    }
    clean.faces.push_back(g);
  }
  for (const Tri& f : clean.faces) {
    if (mesh.add_face(vertices[f[0]], vertices[f[1]], vertices[f[2]]) == SurfaceMesh::null_face()) {
      throw input_error(source, manifold_problem(clean));
    }
  }
  if (!CGAL::is_triangle_mesh(mesh)) throw input_error(source, "not a triangle mesh");
  if (!CGAL::is_closed(mesh)) {
    size_t border_edges = 0;
    for (auto h : mesh.halfedges()) {
      if (mesh.is_border(h)) ++border_edges;
    }
    throw input_error(source, "open surface: " + std::to_string(border_edges) +
                                  " border edges (expected a closed surface; fill the holes first, e.g. with "
                                  "MeshLab's 'Close Holes')");
  }
  if (PMP::does_self_intersect(mesh)) {
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
    PMP::self_intersections(mesh, std::back_inserter(pairs));
    std::string example;
    if (!pairs.empty()) {
      example = " (e.g. faces " + std::to_string(static_cast<size_t>(pairs.front().first)) + " and " +
                std::to_string(static_cast<size_t>(pairs.front().second)) + ")";
    }
    throw input_error(source, "self-intersecting: " + std::to_string(pairs.size()) + " pairs of faces intersect" +
                                  example + "; repair the surface first");
  }
  if (!PMP::does_bound_a_volume(mesh)) {
    throw input_error(source, "does not bound a volume (its closed parts are nested or oriented inconsistently: "
                              "a cavity must be oriented opposite to the part around it)");
  }
  if (!PMP::is_outward_oriented(mesh)) {
    for (Tri& f : clean.faces) std::swap(f[1], f[2]);
    notes.push_back("surface " + source + " was oriented inward: its faces were reversed");
  }
  // Closed and consistently oriented, so this is the enclosed volume (about
  // the first point, not the origin, so far-off coordinates do not cancel).
  TriangleMesh local = clean;
  for (Vec3& p : local.points) p -= clean.points.front();
  const double volume = surface_volume(local);
  if (!(volume > kFlatTolerance * size * size * size)) {
    throw input_error(source, "encloses almost no volume (" + format_number(volume) + " m^3 inside a bounding box " +
                                  format_number(size) + " m across); expected a solid organ");
  }
  return clean;
}

}  // namespace organsim
