#pragma once
// The surface-contact pass of the CPU backend (Pass::SurfaceContact): a
// pushing sphere or capsule against the Model's boundary triangles
// (force_law::capsule_triangle_penalty, the sphere's when its segment has
// zero length), giving each touched point the sum
// of w_p(t) f(t) over its touching triangles t, in ascending t (the order
// step.comp gathers them in). The kernels then add these forces in their
// tool pass (add_tool_force with ToolTerm::Surface), which also sums the
// reaction, so the reaction is minus exactly what the tissue receives.
//
// Broad phase: the tool (its segment's box grown by the radius) against
// each triangle's bounding box at the current positions, so a triangle away from the tool costs a box test and
// an untouched point nothing in the kernels. One thread, in triangle order:
// the result does not depend on the thread count.
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "core/model/model.h"
#include "core/physics/force_law.h"

namespace organsim {

template <class Real>
class SurfaceContact {
 public:
  // Triangles and shares from `model` (a rebuild calls it again: cuts
  // change the surface); `scale` is the backend's Model::tool_k_scale,
  // `lanes` the length of the per-point slot array the kernels read
  // (padding included, -1 there).
  void pack(const Model& model, const std::vector<Real>& scale, size_t lanes) {
    local_of_point_.assign(model.npoint(), -1);
    points_.clear();
    for (int32_t p = 0; p < model.npoint(); ++p)
      if (model.surface_count(p) > 0) {
        local_of_point_[p] = static_cast<int32_t>(points_.size());
        points_.push_back(p);
      }
    tris_.resize(model.surface.size());
    for (auto& v : corner_) v.resize(tris_.size());
    near_.assign(tris_.size(), 0);
    for (size_t t = 0; t < tris_.size(); ++t)
      for (int k = 0; k < 3; ++k) corner_[k][t] = tris_[t][k] = local_of_point_[model.surface[t][k]];
    share_.resize(points_.size());
    for (size_t i = 0; i < points_.size(); ++i)
      share_[i] = scale[points_[i]] / static_cast<Real>(model.surface_count(points_[i]));
    for (auto* v : {&x_, &y_, &z_}) v->assign(points_.size(), 0);
    slot_.assign(lanes, -1);
    force_.clear();
    touched_.clear();
  }

  // Forces for the tool (the segment a-b, a == b for a sphere's centre;
  // radius R, penalty k N/m) with every surface point at position(p, x[3])
  // (internal id p).
  template <class Position>
  void evaluate(Position position, const Real seg_a[3], const Real seg_b[3], Real radius, Real k) {
    for (int32_t p : touched_) slot_[p] = -1;
    touched_.clear();
    force_.clear();
    const size_t n = points_.size();
    for (size_t i = 0; i < n; ++i) {
      Real x[3];
      position(points_[i], x);
      x_[i] = x[0], y_[i] = x[1], z_[i] = x[2];
    }
    using V3 = Eigen::Matrix<Real, 3, 1>;
    const V3 sa(seg_a[0], seg_a[1], seg_a[2]), sb(seg_b[0], seg_b[1], seg_b[2]);
    const Real r2 = radius * radius;
    // Broad phase, vectorised over triangles: the squared distance from the
    // segment's box (the centre, for a sphere) to each triangle's box.
    const int32_t ntri = static_cast<int32_t>(tris_.size());
    const int32_t* __restrict ta = corner_[0].data();
    const int32_t* __restrict tb = corner_[1].data();
    const int32_t* __restrict tc = corner_[2].data();
    uint8_t* __restrict near = near_.data();
    const Real* __restrict X = x_.data();
    const Real* __restrict Y = y_.data();
    const Real* __restrict Z = z_.data();
    const Real lx = std::min(sa[0], sb[0]), ly = std::min(sa[1], sb[1]), lz = std::min(sa[2], sb[2]);
    const Real hx = std::max(sa[0], sb[0]), hy = std::max(sa[1], sb[1]), hz = std::max(sa[2], sb[2]);
#pragma omp simd
    for (int32_t t = 0; t < ntri; ++t) {
      // The gap between [plo, phi] and the triangle's extent along one axis.
      auto gap = [](Real plo, Real phi, Real u, Real v, Real w) {
        const Real lo = u < v ? (u < w ? u : w) : (v < w ? v : w), hi = u > v ? (u > w ? u : w) : (v > w ? v : w);
        return phi < lo ? lo - phi : plo > hi ? plo - hi : Real(0);
      };
      const Real gx = gap(lx, hx, X[ta[t]], X[tb[t]], X[tc[t]]);
      const Real gy = gap(ly, hy, Y[ta[t]], Y[tb[t]], Y[tc[t]]);
      const Real gz = gap(lz, hz, Z[ta[t]], Z[tb[t]], Z[tc[t]]);
      near[t] = gx * gx + gy * gy + gz * gz < r2;
    }
    for (int32_t i = 0; i < ntri; ++i) {
      if (!near[i]) continue;
      const auto& t = tris_[i];
      const V3 a(x_[t[0]], y_[t[0]], z_[t[0]]), b(x_[t[1]], y_[t[1]], z_[t[1]]), e(x_[t[2]], y_[t[2]], z_[t[2]]);
      const Real share[3] = {share_[t[0]], share_[t[1]], share_[t[2]]};
      V3 f;
      Real w[3];
      if (!force_law::capsule_triangle_penalty(sa, sb, radius, a, b, e, k, share, f, w)) continue;
      for (int j = 0; j < 3; ++j) {
        const int32_t p = points_[t[j]];
        if (slot_[p] < 0) {
          slot_[p] = static_cast<int32_t>(touched_.size());
          touched_.push_back(p);
          force_.insert(force_.end(), 3, Real(0));
        }
        Real* fp = &force_[3 * static_cast<size_t>(slot_[p])];
        for (int axis = 0; axis < 3; ++axis) fp[axis] += w[j] * f[axis];
      }
    }
  }

  // Per point (lanes): index into force() or -1; 3 per touched point.
  const int32_t* slot() const { return slot_.data(); }
  const Real* force() const { return force_.data(); }
  int32_t touched() const { return static_cast<int32_t>(touched_.size()); }
  int32_t triangles() const { return static_cast<int32_t>(tris_.size()); }

 private:
  std::vector<int32_t> points_;          // surface points' internal ids, ascending
  std::vector<int32_t> local_of_point_;  // index into points_ or -1 (npoint)
  std::vector<std::array<int32_t, 3>> tris_;  // corners as indices into points_
  std::array<std::vector<int32_t>, 3> corner_;  // the same, one array per corner (the broad phase's gathers)
  std::vector<uint8_t> near_;                  // per triangle: its box comes within the radius of the segment's box
  std::vector<Real> share_;              // s_p / n_p per surface point (force_law::sphere_triangle_penalty)
  std::vector<Real> x_, y_, z_;          // surface points' positions this substep
  std::vector<int32_t> slot_;            // per lane
  std::vector<Real> force_;              // per touched point, 3 each
  std::vector<int32_t> touched_;         // touched points in order of first touch
};

}  // namespace organsim
