#include <array>

#include "core/mesh/tet_mesh.h"
#include "core/util/error.h"

namespace organsim {

TetMesh make_box_tet_mesh(const Vec3& min, const Vec3& max, int nx, int ny, int nz) {
  if (nx < 1 || ny < 1 || nz < 1 || !((max - min).array() > 0).all())
    throw Error(ErrorKind::Input, "make_box_tet_mesh: expected max > min and at least one cell per axis");
  TetMesh mesh;
  auto id = [&](int i, int j, int k) { return static_cast<int32_t>((k * (ny + 1) + j) * (nx + 1) + i); };
  const Vec3 h = (max - min).cwiseQuotient(Vec3(nx, ny, nz));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) mesh.points.push_back(min + Vec3(i * h.x(), j * h.y(), k * h.z()));

  // Kuhn subdivision: every cube is cut along its (0,0,0)-(1,1,1) diagonal
  // into 6 tets, one per axis order; the same diagonal everywhere keeps the
  // faces of neighbouring cubes conforming.
  const std::array<std::array<int, 3>, 6> orders{{{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& order : orders) {
          std::array<int, 3> c{i, j, k};
          Tet tet;
          tet[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[order[s]];
            tet[s + 1] = id(c[0], c[1], c[2]);
          }
          const auto& p = mesh.points;
          if (signed_volume(p[tet[0]], p[tet[1]], p[tet[2]], p[tet[3]]) < 0) std::swap(tet[2], tet[3]);
          mesh.tets.push_back(tet);
        }
  return mesh;
}

}  // namespace organsim
