// CGAL Mesh_3 on a polyhedral domain (the only TU that instantiates Mesh_3).
#include "meshing/mesh_3.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_3.h>
#include <CGAL/Random.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>

#include "meshing/complex_to_tet_mesh.h"

namespace organsim {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using Domain = CGAL::Polyhedral_mesh_domain_3<SurfaceMesh, Kernel>;
// Sequential: the parallel mesher is not deterministic.
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;
constexpr unsigned kSeed = 0;
}  // namespace

struct Mesh3Domain::Impl {
  SurfaceMesh surface;
  CGAL::Random random{kSeed};
  std::unique_ptr<Domain> domain;
};

Mesh3Domain::Mesh3Domain(const TriangleMesh& checked_surface) : impl_(std::make_unique<Impl>()) {
  std::vector<SurfaceMesh::Vertex_index> vertices;
  vertices.reserve(checked_surface.points.size());
  for (const Vec3& p : checked_surface.points) {
    vertices.push_back(impl_->surface.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z())));
  }
  for (const Tri& f : checked_surface.faces) impl_->surface.add_face(vertices[f[0]], vertices[f[1]], vertices[f[2]]);
  impl_->domain = std::make_unique<Domain>(impl_->surface, &impl_->random);
}

Mesh3Domain::~Mesh3Domain() = default;

TetMesh Mesh3Domain::mesh(const Mesh3Criteria& c) const {
  using namespace CGAL::parameters;
  // Same random state for every run: identical criteria give identical meshes,
  // whatever was meshed before in this process.
  impl_->random = CGAL::Random(kSeed);
  CGAL::get_default_random() = CGAL::Random(kSeed);
  const Criteria criteria(facet_angle = 25, facet_size = c.cell_size, facet_distance = c.facet_distance,
                          cell_radius_edge_ratio = 3, cell_size = c.cell_size);
  // Exudation without an explicit limit stops after as much wall-clock time
  // as refinement took, so the same input gave different meshes from run to
  // run; time_limit = 0 means no limit: it runs to completion, deterministic.
  const Complex complex = c.exude ? CGAL::make_mesh_3<Complex>(*impl_->domain, criteria,
                                                               perturb(time_limit = 0, sliver_bound = 10),
                                                               exude(time_limit = 0))
                                  : CGAL::make_mesh_3<Complex>(*impl_->domain, criteria, no_perturb(), no_exude());

  return complex_to_tet_mesh(complex, /*labels=*/false);
}

}  // namespace organsim
