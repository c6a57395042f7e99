// Tet mesh counts and quality measures (see mesh_stats.h).
#include "core/mesh/mesh_stats.h"

#include "core/mesh/boundary.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

namespace organsim {

namespace {

// The four faces of a positively oriented tet (a, b, c, d), each counter-
// clockwise seen from outside: (b,c,d), (a,d,c), (a,b,d), (a,c,b).
constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct TetQuality {
  double min_dihedral, max_dihedral, radius_edge, volume;
};

TetQuality tet_quality(const Vec3 p[4]) {
  TetQuality q{};
  Vec3 normal[4];
  for (int f = 0; f < 4; ++f) {
    const Vec3& a = p[kFaces[f][0]];
    normal[f] = (p[kFaces[f][1]] - a).cross(p[kFaces[f][2]] - a).normalized();
  }
  // The dihedral angle at the edge two faces share is pi minus the angle of
  // their outward normals.
  q.min_dihedral = std::numeric_limits<double>::infinity();
  q.max_dihedral = 0;
  for (int f = 0; f < 4; ++f) {
    for (int g = f + 1; g < 4; ++g) {
      const double cosine = std::clamp(-normal[f].dot(normal[g]), -1.0, 1.0);
      const double angle = std::acos(cosine) * 180.0 / std::numbers::pi;
      q.min_dihedral = std::min(q.min_dihedral, angle);
      q.max_dihedral = std::max(q.max_dihedral, angle);
    }
  }
  // Circumcentre relative to p0: (|a|^2 b x c + |b|^2 c x a + |c|^2 a x b) / (2 a.(b x c)).
  const Vec3 a = p[1] - p[0], b = p[2] - p[0], c = p[3] - p[0];
  const double det = a.dot(b.cross(c));
  const Vec3 centre = (a.squaredNorm() * b.cross(c) + b.squaredNorm() * c.cross(a) + c.squaredNorm() * a.cross(b)) /
                      (2.0 * det);
  double shortest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) shortest = std::min(shortest, (p[i] - p[j]).norm());
  }
  q.radius_edge = centre.norm() / shortest;
  q.volume = det / 6.0;
  return q;
}

}  // namespace

std::vector<Edge> unique_edges(const TetMesh& mesh) {
  std::vector<uint64_t> keys;
  keys.reserve(mesh.tets.size() * 6);
  for (const Tet& t : mesh.tets) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        const auto a = static_cast<uint32_t>(std::min(t[i], t[j]));
        const auto b = static_cast<uint32_t>(std::max(t[i], t[j]));
        keys.push_back(static_cast<uint64_t>(a) << 32 | b);
      }
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<Edge> edges;
  edges.reserve(keys.size());
  for (uint64_t k : keys) edges.push_back({static_cast<int32_t>(k >> 32), static_cast<int32_t>(k & 0xffffffffu)});
  return edges;
}

std::vector<Tri> boundary_triangles(const TetMesh& mesh) { return extract_boundary_faces(mesh.tets); }

double tet_mesh_volume(const TetMesh& mesh) {
  double volume = 0;
  for (const Tet& t : mesh.tets) {
    volume += signed_volume(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]);
  }
  return volume;
}

double surface_volume(const TriangleMesh& surface) {
  // Sum of the signed volumes of the tets (origin, face).
  double volume = 0;
  for (const Tri& f : surface.faces) {
    volume += surface.points[f[0]].dot(surface.points[f[1]].cross(surface.points[f[2]])) / 6.0;
  }
  return volume;
}

MeshReport describe_tet_mesh(const TetMesh& mesh) {
  MeshReport report;
  report.points = static_cast<int32_t>(mesh.points.size());
  report.tets = static_cast<int32_t>(mesh.tets.size());
  const std::vector<Edge> edges = unique_edges(mesh);
  report.springs = static_cast<int32_t>(edges.size());
  report.boundary_triangles = static_cast<int32_t>(boundary_triangles(mesh).size());

  std::vector<int32_t> valence(mesh.points.size(), 0);
  for (const Edge& e : edges) {
    ++valence[e[0]];
    ++valence[e[1]];
  }
  for (int32_t v : valence) {
    if (static_cast<size_t>(v) >= report.valence_histogram.size()) report.valence_histogram.resize(v + 1, 0);
    ++report.valence_histogram[v];
  }

  if (!mesh.tets.empty()) {
    MeshQuality& q = report.quality;
    q.min_dihedral_deg = std::numeric_limits<double>::infinity();
    q.min_tet_volume = std::numeric_limits<double>::infinity();
    for (const Tet& t : mesh.tets) {
      const Vec3 p[4] = {mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]};
      const TetQuality tq = tet_quality(p);
      q.min_dihedral_deg = std::min(q.min_dihedral_deg, tq.min_dihedral);
      q.max_dihedral_deg = std::max(q.max_dihedral_deg, tq.max_dihedral);
      q.max_radius_edge_ratio = std::max(q.max_radius_edge_ratio, tq.radius_edge);
      q.min_tet_volume = std::min(q.min_tet_volume, tq.volume);
    }
  }
  report.labels = label_stats(mesh);
  return report;
}

std::vector<LabelStats> label_stats(const TetMesh& mesh) {
  std::map<int32_t, LabelStats> by_label;
  for (size_t t = 0; t < mesh.labels.size(); ++t) {
    LabelStats& s = by_label[mesh.labels[t]];
    s.label = mesh.labels[t];
    ++s.tets;
    const Tet& k = mesh.tets[t];
    s.mesh_volume += signed_volume(mesh.points[k[0]], mesh.points[k[1]], mesh.points[k[2]], mesh.points[k[3]]);
  }
  std::vector<LabelStats> stats;
  for (auto& [label, s] : by_label) stats.push_back(s);
  return stats;
}

std::optional<double> LabelStats::relative_difference() const {
  if (!image_volume || !(*image_volume > 0)) return std::nullopt;
  return std::abs(mesh_volume - *image_volume) / *image_volume;
}

namespace {
double mean_valence(const MeshReport& r) { return r.points > 0 ? 2.0 * r.springs / r.points : 0.0; }
}  // namespace

std::string format_mesh_report(const MeshReport& r) {
  std::ostringstream out;
  out << "points " << r.points << ", springs " << r.springs << ", tets " << r.tets << ", boundary triangles "
      << r.boundary_triangles << "\n";
  out.precision(3);
  out << "dihedral angles " << std::fixed << r.quality.min_dihedral_deg << " .. " << r.quality.max_dihedral_deg
      << " deg, max radius-edge ratio " << r.quality.max_radius_edge_ratio << ", min tet volume "
      << std::scientific << r.quality.min_tet_volume << " m^3\n";
  out << std::fixed << "springs per point (mean " << mean_valence(r) << "):\n";
  // Text bars scaled to the most common valence (the paper's Figure 2).
  const int32_t peak = r.valence_histogram.empty()
                           ? 0
                           : *std::max_element(r.valence_histogram.begin(), r.valence_histogram.end());
  constexpr int kBarWidth = 50;
  for (size_t k = 0; k < r.valence_histogram.size(); ++k) {
    const int32_t count = r.valence_histogram[k];
    if (count == 0) continue;
    const int width = peak > 0 ? std::max(1, static_cast<int>(std::lround(double(count) * kBarWidth / peak))) : 0;
    char label[32];
    std::snprintf(label, sizeof label, "%4zu %7d ", k, count);
    out << "  " << label << std::string(static_cast<size_t>(width), '#') << "\n";
  }
  for (const LabelStats& l : r.labels) {
    out << std::defaultfloat << std::setprecision(4) << "label " << l.label << (l.name.empty() ? "" : " (" + l.name + ")")
        << ": " << l.tets << " tets, volume " << l.mesh_volume << " m^3";
    if (l.image_volume) {
      out << " (image " << *l.image_volume << " m^3, " << std::fixed << std::setprecision(1)
          << 100.0 * l.relative_difference().value_or(0) << " % off)";
    }
    out << "\n";
  }
  for (const std::string& note : r.notes) out << "note: " << note << "\n";
  for (const std::string& warning : r.warnings) out << "warning: " << warning << "\n";
  out.precision(2);
  out << "time " << std::fixed << r.seconds << " s\n";
  return out.str();
}

nlohmann::json mesh_report_json(const MeshReport& r) {
  nlohmann::json j;
  j["points"] = r.points;
  j["springs"] = r.springs;
  j["tets"] = r.tets;
  j["boundary_triangles"] = r.boundary_triangles;
  j["quality"] = {{"min_dihedral_deg", r.quality.min_dihedral_deg},
                  {"max_dihedral_deg", r.quality.max_dihedral_deg},
                  {"max_radius_edge_ratio", r.quality.max_radius_edge_ratio},
                  {"min_tet_volume_m3", r.quality.min_tet_volume}};
  int32_t max_valence = 0;
  for (size_t k = 0; k < r.valence_histogram.size(); ++k) {
    if (r.valence_histogram[k] > 0) max_valence = static_cast<int32_t>(k);
  }
  j["springs_per_point"] = {{"mean", mean_valence(r)}, {"max", max_valence}, {"histogram", r.valence_histogram}};
  j["seconds"] = r.seconds;
  j["notes"] = r.notes;
  if (!r.warnings.empty()) j["warnings"] = r.warnings;
  if (!r.labels.empty()) {
    nlohmann::json labels = nlohmann::json::array();
    for (const LabelStats& l : r.labels) {
      nlohmann::json e = {{"label", l.label}, {"tets", l.tets}, {"mesh_volume_m3", l.mesh_volume}};
      if (!l.name.empty()) e["name"] = l.name;
      if (l.image_volume) {
        e["image_volume_m3"] = *l.image_volume;
        e["relative_difference"] = l.relative_difference().value_or(0);
      }
      labels.push_back(e);
    }
    j["labels"] = labels;
  }
  return j;
}

}  // namespace organsim
