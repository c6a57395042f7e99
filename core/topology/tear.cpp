#include "core/topology/tear.h"

#include <algorithm>
#include <cmath>

namespace organsim {

namespace {

// The interior, unseparated face most perpendicular to direction `l` among
// the tets that hold both ends of the spring (lowest face id on a tie), or -1.
int32_t face_across(const Model& model, const std::vector<Vec3>& x, const TetFaces& faces,
                    const std::vector<uint8_t>& separated, const std::vector<uint8_t>& chosen, const Edge& ends,
                    const Vec3& l) {
  int32_t best = -1;
  double best_score = -1;
  for (int32_t t = 0; t < model.ntet(); ++t) {
    const Tet& tet = model.tet_points[t];
    if (std::find(tet.begin(), tet.end(), ends[0]) == tet.end() ||
        std::find(tet.begin(), tet.end(), ends[1]) == tet.end())
      continue;
    for (int i = 0; i < 4; ++i) {
      const int32_t f = faces.face_of_tet[t][i];
      if (f < 0 || separated[f] || chosen[f]) continue;
      const Tri v = tet_face(tet, i);
      const Vec3 n = (x[v[1]] - x[v[0]]).cross(x[v[2]] - x[v[0]]);
      const double norm = n.norm();
      if (!(norm > 0)) continue;
      const double score = std::abs(n.dot(l)) / norm;
      if (score > best_score || (score == best_score && f < best)) {
        best = f;
        best_score = score;
      }
    }
  }
  return best;
}

}  // namespace

std::vector<int32_t> TearDetector::update(const Model& model, const std::vector<Vec3>& x, const TetFaces& faces,
                                          const std::vector<uint8_t>& separated) {
  over_.resize(model.nspring(), 0);
  std::vector<int32_t> out;
  std::vector<uint8_t> chosen;
  for (int32_t s = 0; s < model.first_suture(); ++s) {  // tissue tears; a suture has no face to separate
    const auto [a, b] = model.spring_ends[s];
    const Vec3 l = x[b] - x[a];
    const double strain = (l.norm() - model.spring_rest[s]) / model.spring_rest[s];
    over_[s] = strain > settings_.strain ? over_[s] + 1 : 0;
    if (over_[s] < settings_.ticks || static_cast<int32_t>(out.size()) >= settings_.max_per_tick) continue;
    if (chosen.empty()) chosen.assign(faces.nface(), 0);
    const int32_t f = face_across(model, x, faces, separated, chosen, model.spring_ends[s], l / l.norm());
    if (f < 0) continue;
    chosen[f] = 1;
    out.push_back(f);
    over_[s] = 0;  // it counts again from zero on the new configuration
  }
  std::sort(out.begin(), out.end());
  return out;
}

void TearDetector::model_changed(const Model& previous, const Model& next) {
  std::vector<int32_t> carried(next.nspring(), 0);
  over_.resize(previous.nspring(), 0);
  // The tissue's spring ends are sorted in both models: one merge pass.
  for (int32_t i = 0, j = 0; i < previous.first_suture() && j < next.first_suture();) {
    if (previous.spring_ends[i] < next.spring_ends[j]) {
      ++i;
    } else if (next.spring_ends[j] < previous.spring_ends[i]) {
      ++j;
    } else {
      carried[j++] = over_[i++];
    }
  }
  over_ = std::move(carried);
}

}  // namespace organsim
