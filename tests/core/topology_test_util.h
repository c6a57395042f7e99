#pragma once
// The invariants every topology change must keep (issue 8), as one check
// that returns what is wrong (empty when all hold), so tests can assert it
// after every change and print the first problem.
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>

#include "core/mesh/boundary.h"
#include "core/mesh/tet_mesh.h"
#include "core/model/model.h"
#include "core/run/run.h"
#include "core/scenario/scenario.h"
#include "core/sim/run_observer.h"
#include "core/topology/blade.h"

namespace organsim::testing {

// A blade 0.8 long somewhere in the unit box, moving a short way (up to 0.3
// per axis) in a random direction: the random cuts of the topology tests.
inline BladeSweep random_short_blade(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const Vec3 a0(u(rng), u(rng), u(rng));
  const Vec3 b0 = a0 + 0.8 * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
  const Vec3 move = 0.6 * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
  return {a0, b0, a0 + move, b0 + move};
}

inline std::string topology_problems(const Model& m) {
  const int32_t n = m.npoint();
  // Each face shared by at most two tets; positive rest volumes.
  std::map<Tri, int> face_count;
  for (int32_t t = 0; t < m.ntet(); ++t) {
    const Tet& k = m.tet_points[t];
    for (int32_t p : k)
      if (p < 0 || p >= n) return "tet " + std::to_string(t) + " has point " + std::to_string(p) + " out of range";
    const double v = signed_volume(m.rest_position[k[0]], m.rest_position[k[1]], m.rest_position[k[2]],
                                   m.rest_position[k[3]]);
    if (!(v > 0)) return "tet " + std::to_string(t) + " has rest volume " + std::to_string(v);
    for (int i = 0; i < 4; ++i) {
      Tri f{};
      for (int a = 0, c = 0; a < 4; ++a)
        if (a != i) f[c++] = k[a];
      std::sort(f.begin(), f.end());
      if (++face_count[f] > 2) return "a face of tet " + std::to_string(t) + " is shared by more than two tets";
    }
  }
  // The tissue's springs are exactly the unique tet edges; the sutures follow
  // them, each joining two different points in range.
  std::set<Edge> edges;
  for (const Tet& k : m.tet_points)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edges.insert({std::min(k[i], k[j]), std::max(k[i], k[j])});
  const std::set<Edge> springs(m.spring_ends.begin(), m.spring_ends.begin() + m.first_suture());
  if (springs.size() != static_cast<size_t>(m.first_suture())) return "duplicate springs";
  for (int32_t s = m.first_suture(); s < m.nspring(); ++s) {
    const Edge e = m.spring_ends[s];
    if (e != m.suture_of_spring(s).ends || !(0 <= e[0] && e[0] < e[1] && e[1] < n))
      return "suture spring " + std::to_string(s) + " does not join its suture's two points";
  }
  if (springs != edges) return "the springs are not the tets' edges (" + std::to_string(springs.size()) + " vs " +
                               std::to_string(edges.size()) + ")";
  // Masses from each point's own tets.
  std::vector<double> mass(n, 0.0);
  for (int32_t t = 0; t < m.ntet(); ++t)
    for (int32_t p : m.tet_points[t]) mass[p] += m.material.density * m.tet_rest_volume[t] / 4;
  for (int32_t p = 0; p < n; ++p)
    if (std::abs(mass[p] - m.mass[p]) > 1e-12 * mass[p])
      return "point " + std::to_string(p) + " has mass " + std::to_string(m.mass[p]) + ", its tets give " +
             std::to_string(mass[p]);
  // The gather layout holds exactly each point's springs and tets.
  const GatherLayout& L = m.layout;
  std::vector<std::multiset<int32_t>> spring_slots(n), tet_slots(n);
  for (int32_t e = 0; e < static_cast<int32_t>(L.springs.item.size()); ++e) {
    const int32_t s = L.springs.item[e];
    if (s < 0) continue;
    const int32_t p = point_of_entry(L.springs, L.chunk_size, e);
    if (p >= n) return "spring slot of a point out of range";
    spring_slots[p].insert(s);
    if (L.spring_other[e] != m.spring_ends[s][0] + m.spring_ends[s][1] - p) return "wrong other end in a spring slot";
  }
  for (int32_t e = 0; e < static_cast<int32_t>(L.tets.item.size()); ++e) {
    const int32_t t = L.tets.item[e];
    if (t < 0) continue;
    const int32_t p = point_of_entry(L.tets, L.chunk_size, e);
    if (p >= n) return "tet slot of a point out of range";
    tet_slots[p].insert(t);
  }
  std::vector<std::multiset<int32_t>> want_springs(n), want_tets(n);
  for (int32_t s = 0; s < m.nspring(); ++s) {
    want_springs[m.spring_ends[s][0]].insert(s);
    want_springs[m.spring_ends[s][1]].insert(s);
  }
  for (int32_t t = 0; t < m.ntet(); ++t)
    for (int32_t p : m.tet_points[t]) want_tets[p].insert(t);
  for (int32_t p = 0; p < n; ++p) {
    if (spring_slots[p] != want_springs[p]) return "point " + std::to_string(p) + ": spring slots differ from its springs";
    if (tet_slots[p] != want_tets[p]) return "point " + std::to_string(p) + ": tet slots differ from its tets";
  }
  // The boundary is a closed, oriented 2-manifold.
  const SurfaceTopology topo = surface_topology(extract_boundary_faces(m.tet_points));
  if (!topo.closed_and_oriented())
    return "boundary not closed and oriented: " + std::to_string(topo.border_edges) + " border, " +
           std::to_string(topo.nonmanifold_edges) + " non-manifold, " + std::to_string(topo.misoriented_edges) +
           " misoriented edges";
  return "";
}

// Connected components of the points through tets (union-find), labelled 0.. in order of first point.
inline std::vector<int32_t> point_components(const Model& m, int32_t* count) {
  std::vector<int32_t> parent(m.npoint());
  for (int32_t i = 0; i < m.npoint(); ++i) parent[i] = i;
  auto find = [&](int32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const Tet& k : m.tet_points)
    for (int i = 1; i < 4; ++i) parent[find(k[i])] = find(k[0]);
  std::vector<int32_t> label(m.npoint(), -1), of_root(m.npoint(), -1);
  int32_t next = 0;
  for (int32_t i = 0; i < m.npoint(); ++i) {
    const int32_t r = find(i);
    if (of_root[r] < 0) of_root[r] = next++;
    label[i] = of_root[r];
  }
  if (count) *count = next;
  return label;
}

// Watches a run with topology events: counts the changes, keeps a copy of
// the last Model version (the run loop frees its versions when it returns)
// and, with keep_positions, the positions after every tick.
struct TopologyRecorder final : RunObserver {
  bool keep_positions = false;
  std::vector<std::vector<Vec3>> x;  // per tick (ntick x npoint of that tick)
  std::optional<Model> last;
  int changes = 0;
  void on_tick(const Model&, Backend& backend, const TickInfo&) override {
    if (!keep_positions) return;
    x.emplace_back();
    backend.positions(x.back());
  }
  void on_topology_changed(const Model& next, Backend&) override {
    ++changes;
    last = next;
  }
};

// A 4 cm soft block (4 x 4 x 4 cubes of 1 cm) hanging from its top face under
// gravity, without drag so that a freed part falls freely. A blade edge
// along y sweeps the plane z = 2 cm (a grid plane) from x = -1 cm to 5 cm
// within one 1 ms tick at t = 20 ms.
inline Scenario hanging_block() {
  Scenario s;
  s.file = "hanging_block.json";
  s.material.density = 1000;
  s.material.young_modulus = 5000;
  s.material.spring_damping_time = 1e-3;
  s.material.volume_modulus = 10000;
  s.material.viscous_damping = 0;  // drag would slow the fall
  FixedSelector top;
  top.kind = FixedSelector::Kind::Plane;
  top.point = Vec3(0, 0, 0.04 - 1e-6);
  top.normal = Vec3(0, 0, 1);
  s.fixed = {top};
  s.time.duration = 0.06;
  s.time.dt = 1e-4;
  s.time.substeps = 10;
  CutEvent cut;
  cut.name = "through";
  cut.keyframes = {{0.020, Vec3(-0.01, -0.01, 0.02), Vec3(-0.01, 0.05, 0.02)},
                   {0.021, Vec3(0.05, -0.01, 0.02), Vec3(0.05, 0.05, 0.02)}};
  s.events.cuts = {cut};
  return s;
}

inline Model block_model(const Scenario& s) {
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 4, 4, 4), s.material, model_options(s),
                     "block");
}

}  // namespace organsim::testing
