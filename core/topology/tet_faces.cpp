#include "core/topology/tet_faces.h"

#include <algorithm>
#include <string>

#include "core/util/error.h"

namespace organsim {

TetFaces build_tet_faces(const std::vector<Tet>& tets) {
  struct Key {
    Tri sorted;
    int32_t tet;
    int8_t local;
  };
  std::vector<Key> keys;
  keys.reserve(tets.size() * 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int i = 0; i < 4; ++i) {
      Tri f = tet_face(tets[t], i);
      std::sort(f.begin(), f.end());
      keys.push_back({f, static_cast<int32_t>(t), static_cast<int8_t>(i)});
    }
  }
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
    return a.sorted != b.sorted ? a.sorted < b.sorted : a.tet < b.tet;
  });
  TetFaces faces;
  faces.face_of_tet.assign(tets.size(), {-1, -1, -1, -1});
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j].sorted == keys[i].sorted) ++j;
    if (j - i > 2) {
      throw Error(ErrorKind::Input, "face (" + std::to_string(keys[i].sorted[0]) + ", " +
                                        std::to_string(keys[i].sorted[1]) + ", " + std::to_string(keys[i].sorted[2]) +
                                        ") is shared by " + std::to_string(j - i) + " tets (expected at most 2)");
    }
    if (j - i == 2) {
      const int32_t id = faces.nface();
      faces.tets.push_back({keys[i].tet, keys[i + 1].tet});
      faces.local.push_back({keys[i].local, keys[i + 1].local});
      faces.face_of_tet[keys[i].tet][keys[i].local] = id;
      faces.face_of_tet[keys[i + 1].tet][keys[i + 1].local] = id;
    }
    i = j;
  }
  return faces;
}

}  // namespace organsim
