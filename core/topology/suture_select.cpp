#include "core/topology/suture_select.h"

#include <algorithm>
#include <set>
#include <string>

#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {

Error event_error(const SutureEvent& event, const std::string& field, const std::string& message) {
  return Error(ErrorKind::Scenario, event.where + (field.empty() ? "" : "." + field) + ": " + message);
}

Suture make_suture(const SutureEvent& event, double t, const Model& model, const std::vector<Vec3>& x, int32_t a,
                   int32_t b) {
  Suture s;
  s.ends = {std::min(a, b), std::max(a, b)};
  s.k = event.stiffness * std::min(model.tool_scale(a), model.tool_scale(b));
  s.tied_at = t;
  s.length = event.tied_length((x[b] - x[a]).norm());
  s.rate = event.rate;
  s.min_length = event.min_length;
  return s;
}

std::vector<Suture> explicit_pairs(const SutureEvent& event, double t, const Model& model, const std::vector<Vec3>& x) {
  std::vector<Suture> out;
  const int32_t n = model.npoint();
  for (size_t k = 0; k < event.pairs.size(); ++k) {
    int32_t ends[2];
    for (int e = 0; e < 2; ++e) {
      const int32_t id = event.pairs[k][e];
      if (id >= n)
        throw event_error(event, "pairs[" + std::to_string(k) + "][" + std::to_string(e) + "]",
                          "point " + std::to_string(id) + " out of range 0.." + std::to_string(n - 1) +
                              " (the model has " + std::to_string(n) + " points at t = " + format_number(t, "%.6g") +
                              " s; ids from " + std::to_string(model.mesh_points) + " are points cuts appended)");
      ends[e] = model.internal_of_input[id];
    }
    out.push_back(make_suture(event, t, model, x, ends[0], ends[1]));
  }
  return out;
}

// The normal of the blade's swept surface, summed over its keyframe spans.
Vec3 sweep_normal(const CutEvent& cut) {
  Vec3 n = Vec3::Zero();
  for (size_t i = 1; i < cut.keyframes.size(); ++i) {
    const BladeKeyframe &k0 = cut.keyframes[i - 1], &k1 = cut.keyframes[i];
    n += (k0.b - k0.a).cross(0.5 * (k1.a + k1.b) - 0.5 * (k0.a + k0.b));
  }
  return n;
}

Vec3 rest_centroid(const Model& model, const Tet& tet) {
  Vec3 c = Vec3::Zero();
  for (int32_t p : tet) c += model.rest_position[p];
  return 0.25 * c;
}

std::vector<Suture> along_cut(const SutureEvent& event, double t, const Model& model, const std::vector<Vec3>& x,
                              const CutRecord& cut, const TetFaces& faces, const std::vector<uint8_t>& separated) {
  const Vec3 normal = sweep_normal(*cut.cut);
  if (!(normal.squaredNorm() > 0))
    throw event_error(event, "along", "the blade of cut \"" + event.along + "\" sweeps no surface, so it has no sides");
  // Points on the cut faces of each side; a point on both sides (where the
  // cut has not split it, e.g. at the blade's tip) is no candidate.
  std::set<int32_t> side[2];
  for (int32_t f : cut.faces) {
    if (!separated[f]) continue;
    const auto [t0, t1] = faces.tets[f];
    const bool t0_first = (rest_centroid(model, model.tet_points[t1]) - rest_centroid(model, model.tet_points[t0])).dot(normal) > 0;
    for (int k = 0; k < 2; ++k) {
      const int s = (k == 0) == t0_first ? 0 : 1;
      for (int32_t p : tet_face(model.tet_points[faces.tets[f][k]], faces.local[f][k])) side[s].insert(p);
    }
  }
  std::vector<int32_t> candidates, partners;
  std::set_difference(side[0].begin(), side[0].end(), side[1].begin(), side[1].end(), std::back_inserter(candidates));
  std::set_difference(side[1].begin(), side[1].end(), side[0].begin(), side[0].end(), std::back_inserter(partners));
  if (candidates.empty() || partners.empty())
    throw event_error(event, "along", "the cut \"" + event.along + "\" has separated no points by t = " +
                                          format_number(t, "%.6g") + " s, so there is nothing to suture");

  // Along the cut's longest extent, one candidate every `spacing` or more.
  Vec3 lo = model.rest_position[candidates[0]], hi = lo;
  for (int32_t p : candidates) {
    lo = lo.cwiseMin(model.rest_position[p]);
    hi = hi.cwiseMax(model.rest_position[p]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  std::stable_sort(candidates.begin(), candidates.end(), [&](int32_t a, int32_t b) {
    return model.rest_position[a][axis] < model.rest_position[b][axis];
  });
  std::vector<int32_t> chosen;
  for (int32_t p : candidates) {
    const bool apart = std::all_of(chosen.begin(), chosen.end(), [&](int32_t q) {
      return (model.rest_position[p] - model.rest_position[q]).norm() >= event.spacing;
    });
    if (apart) chosen.push_back(p);
  }

  // The mesh point a point was copied from, through copies of copies.
  auto root = [&](int32_t p) {
    while (model.origin[p] != p) p = model.origin[p];
    return p;
  };
  std::set<Edge> tied;
  std::vector<Suture> out;
  for (int32_t p : chosen) {
    // The partner: the copy of the same mesh point on the other side, which
    // the cut separated it from (closing the pair restores the material);
    // else the nearest point on the other side.
    int32_t best = -1;
    double best_d = 0;
    bool best_twin = false;
    for (int32_t q : partners) {
      const double d = (x[q] - x[p]).norm();
      const bool twin = root(q) == root(p);
      if (best < 0 || (twin && !best_twin) || (twin == best_twin && d < best_d)) best = q, best_d = d, best_twin = twin;
    }
    if (best_d > event.max_distance)
      throw event_error(event, "max_distance",
                        "point " + std::to_string(model.input_of_internal[p]) + " on one side of cut \"" +
                            event.along + "\" has no partner within " + format_number(event.max_distance, "%.6g") +
                            " m at t = " + format_number(t, "%.6g") + " s (the nearest, point " +
                            std::to_string(model.input_of_internal[best]) + ", is " + format_number(best_d, "%.6g") +
                            " m away)");
    if (tied.insert({std::min(p, best), std::max(p, best)}).second)
      out.push_back(make_suture(event, t, model, x, p, best));
  }
  return out;
}

}  // namespace

std::vector<Suture> tie_sutures(const SutureEvent& event, double t, const Model& model, const std::vector<Vec3>& x,
                                const CutRecord* cut, const TetFaces& faces, const std::vector<uint8_t>& separated) {
  if (event.along.empty()) return explicit_pairs(event, t, model, x);
  if (!cut || !cut->cut) throw event_error(event, "along", "no cut named \"" + event.along + "\"");
  return along_cut(event, t, model, x, *cut, faces, separated);
}

}  // namespace organsim
