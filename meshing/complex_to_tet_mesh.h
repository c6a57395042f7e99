#pragma once
// A Mesh_3 complex's cells as a TetMesh, for the translation units that
// instantiate Mesh_3 (mesh_3.cpp, mesh_3_image.cpp); includes no CGAL itself.
#include <cstdint>
#include <unordered_map>
#include <utility>

#include "core/mesh/tet_mesh.h"

namespace organsim {

// Indexes only the vertices that cells of the complex use (the triangulation
// also holds vertices outside it), in the order the cells first use them;
// tets positively oriented in our convention; with `labels`, each tet's
// subdomain index in TetMesh::labels.
template <class Complex>
TetMesh complex_to_tet_mesh(const Complex& complex, bool labels) {
  using Triangulation = typename Complex::Triangulation;
  const Triangulation& tr = complex.triangulation();
  TetMesh mesh;
  std::unordered_map<typename Triangulation::Vertex_handle, int32_t> index;
  mesh.tets.reserve(complex.number_of_cells_in_complex());
  for (auto cell = complex.cells_in_complex_begin(); cell != complex.cells_in_complex_end(); ++cell) {
    Tet tet{};
    for (int k = 0; k < 4; ++k) {
      const auto v = cell->vertex(k);
      const auto [it, inserted] = index.try_emplace(v, static_cast<int32_t>(mesh.points.size()));
      if (inserted) {
        const auto& p = tr.point(v);  // a weighted point
        mesh.points.emplace_back(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
      }
      tet[k] = it->second;
    }
    if (signed_volume(mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]], mesh.points[tet[3]]) < 0) {
      std::swap(tet[2], tet[3]);
    }
    mesh.tets.push_back(tet);
    if (labels) mesh.labels.push_back(static_cast<int32_t>(complex.subdomain_index(cell)));
  }
  return mesh;
}

}  // namespace organsim
