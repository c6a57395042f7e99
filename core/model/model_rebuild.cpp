#include "core/model/model_rebuild.h"

#include <cmath>
#include <string>

#include "core/model/model_assembly.h"
#include "core/util/error.h"

namespace organsim {

namespace {

// A change that does not describe the same tets over the same rest geometry
// is a programming error upstream; say which element is wrong.
void validate_change(const Model& previous, const TopologyChange& change) {
  const int32_t old_n = previous.npoint();
  const int32_t new_n = old_n + static_cast<int32_t>(change.appended_origin.size());
  if (change.tet_points.size() != previous.tet_points.size())
    throw Error(ErrorKind::Input, "topology change: expected " + std::to_string(previous.ntet()) + " tets, got " +
                                      std::to_string(change.tet_points.size()));
  for (size_t k = 0; k < change.appended_origin.size(); ++k) {
    const int32_t o = change.appended_origin[k];
    if (o < 0 || o >= old_n)
      throw Error(ErrorKind::Input, "topology change: appended point " + std::to_string(old_n + k) +
                                        " copies point " + std::to_string(o) + ", expected 0.." +
                                        std::to_string(old_n - 1));
  }
  // The mesh point a point descends from, through copies of copies.
  auto root = [&](int32_t p) {
    if (p >= old_n) p = change.appended_origin[p - old_n];
    while (previous.origin[p] != p) p = previous.origin[p];
    return p;
  };
  for (size_t t = 0; t < change.tet_points.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const int32_t v = change.tet_points[t][k];
      if (v < 0 || v >= new_n)
        throw Error(ErrorKind::Input, "topology change: tet " + std::to_string(t) + " vertex " + std::to_string(v) +
                                          " out of range 0.." + std::to_string(new_n - 1));
      // A vertex may only be replaced by a copy of the same original point:
      // then the rest geometry, and so the rest volume, is unchanged.
      if (root(v) != root(previous.tet_points[t][k]))
        throw Error(ErrorKind::Input, "topology change: tet " + std::to_string(t) + " vertex " + std::to_string(k) +
                                          " becomes point " + std::to_string(v) + ", which is not a copy of point " +
                                          std::to_string(previous.tet_points[t][k]));
    }
  }
}

void validate_sutures(const Model& previous, const std::vector<Suture>& sutures) {
  const int32_t n = previous.npoint();
  for (size_t k = 0; k < sutures.size(); ++k) {
    const Suture& u = sutures[k];
    if (!(u.ends[0] >= 0 && u.ends[0] < u.ends[1] && u.ends[1] < n))
      throw Error(ErrorKind::Input, "topology change: suture " + std::to_string(k) + " joins points " +
                                        std::to_string(u.ends[0]) + " and " + std::to_string(u.ends[1]) +
                                        ", expected two different points in 0.." + std::to_string(n - 1) +
                                        " in increasing order");
    if (!(u.k > 0) || !std::isfinite(u.k) || !(u.length >= 0) || !(u.min_length >= 0) || !(u.rate >= 0))
      throw Error(ErrorKind::Input, "topology change: suture " + std::to_string(k) +
                                        " needs k > 0 and length, min_length, rate >= 0");
  }
}

// rebuild_model with `sutures` tied after the previous version's.
Model rebuild_with(const Model& previous, const TopologyChange& change, const std::vector<Suture>& sutures) {
  validate_change(previous, change);
  const int32_t old_n = previous.npoint();
  const int32_t new_n = old_n + static_cast<int32_t>(change.appended_origin.size());

  Model model;
  model.version = previous.version + 1;
  model.mesh_points = previous.mesh_points;
  model.material = previous.material;
  model.materials = previous.materials;
  model.tet_material = previous.tet_material;  // tet ids are kept by every change
  model.tet_label = previous.tet_label;
  model.gravity = previous.gravity;
  model.viscous_damping = previous.viscous_damping;

  // Appended points: internal id == output number, rest state of the origin.
  model.rest_position = previous.rest_position;
  model.origin = previous.origin;
  model.input_of_internal = previous.input_of_internal;
  model.internal_of_input = previous.internal_of_input;
  std::vector<uint8_t> held(new_n);
  for (int32_t i = 0; i < old_n; ++i) held[i] = previous.fixed[i] && previous.mass[i] > 0;
  for (int32_t p = old_n; p < new_n; ++p) {
    const int32_t o = change.appended_origin[p - old_n];
    model.rest_position.push_back(previous.rest_position[o]);
    model.origin.push_back(o);
    model.input_of_internal.push_back(p);
    model.internal_of_input.push_back(p);
    held[p] = held[o];
  }

  model.tet_points = change.tet_points;
  model.tet_rest_volume = previous.tet_rest_volume;
  model.sutures = previous.sutures;
  model.sutures.insert(model.sutures.end(), sutures.begin(), sutures.end());
  assemble_model(model, held, previous.layout.chunk_size, previous.layout.sort_window);
  return model;
}

}  // namespace

Model rebuild_model(const Model& previous, const TopologyChange& change) { return rebuild_with(previous, change, {}); }

Model add_sutures(const Model& previous, const std::vector<Suture>& sutures) {
  validate_sutures(previous, sutures);
  TopologyChange same;
  same.tet_points = previous.tet_points;
  return rebuild_with(previous, same, sutures);
}

}  // namespace organsim
