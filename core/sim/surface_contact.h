#pragma once
// The surface-contact pass of the CPU backend (Pass::SurfaceContact): a
// pushing sphere or capsule, or a grasper's two capsule jaws, against the
// Model's boundary triangles (force_law::capsule_triangle_penalty, the
// sphere's when its segment has zero length), giving each touched point the
// sum of w_p(t) f(t) over its touching triangles t, in ascending t and jaw
// by jaw (the order step.comp gathers them in), each f(t) times its
// force_law::HertzLayer factor with the sub-cell layer (a sphere's or a
// capsule's), then,
// with friction, its anchor_friction force. The kernels then add these forces in their
// tool pass (add_tool_force with ToolTerm::Surface), which also sums the
// reaction, so the reaction is minus exactly what the tissue receives.
//
// Broad phase: the tool (its segment's box grown by the radius) against
// each triangle's bounding box at the current positions, so a triangle away
// from the tool costs a box test and an untouched point nothing in the
// kernels. The box tests are independent per triangle and may run on
// several threads; the penalties are summed on one thread, in triangle
// order: the result does not depend on the thread count.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/model/contact_layer.h"
#include "core/model/model.h"
#include "core/physics/force_law.h"
#include "core/sim/tool.h"

namespace organsim {

template <class Real>
class SurfaceContact {
  using V3 = Eigen::Matrix<Real, 3, 1>;

 public:
  // Triangles and shares from `model` (a rebuild calls it again: cuts
  // change the surface); `scale` is the backend's Model::tool_k_scale,
  // `lanes` the length of the per-point slot array the kernels read
  // (padding included, -1 there); `hertz_layer` puts a sphere's or a
  // capsule's contact in series with the sub-cell layer (force_law::HertzLayer).
  void pack(const Model& model, const std::vector<Real>& scale, size_t lanes, bool hertz_layer = false) {
    local_of_point_.assign(model.npoint(), -1);
    points_.clear();
    for (int32_t p = 0; p < model.npoint(); ++p)
      if (model.surface_count(p) > 0) {
        local_of_point_[p] = static_cast<int32_t>(points_.size());
        points_.push_back(p);
      }
    const size_t ntri = model.surface.size();
    for (auto& v : corner_) v.resize(ntri);
    for (size_t t = 0; t < ntri; ++t)
      for (int k = 0; k < 3; ++k) corner_[k][t] = local_of_point_[model.surface[t][k]];
    // Whole 8-byte words, the tail zero: the narrow phase skips 8 far triangles at a time.
    near_.assign((ntri + 7) / 8 * 8, 0);
    share_.resize(points_.size());
    for (size_t i = 0; i < points_.size(); ++i)
      share_[i] = scale[points_[i]] / static_cast<Real>(model.surface_count(points_[i]));
    layer_.clear();
    if (hertz_layer) {
      const ContactLayer layer = contact_layer(model);
      layer_.reserve(ntri);
      for (const Tri& t : model.surface) layer_.push_back(triangle_layer(layer, t));
      // So that the step never grows them: at most every triangle touches.
      pending_.reserve(ntri);
      hertz_.reserve(ntri);
    }
    for (auto* v : {&x_, &y_, &z_}) v->assign(points_.size(), 0);
    slot_.assign(lanes, -1);
    force_.clear();
    touched_.clear();
    point_scale_.assign(scale.begin(), scale.begin() + model.npoint());
    anchor_.assign(model.npoint(), V3::Zero());
    has_anchor_.assign(model.npoint(), 0);
    anchored_.clear();
    anchored_.reserve(points_.size());  // so that the step never grows it
  }

  // Friction's anchors from the pass of the previous Model version: they are
  // per point id, which a rebuild keeps, so a grip holds through a cut
  // (appended points have none).
  void take_anchors(SurfaceContact& previous) {
    const size_t n = anchor_.size();
    anchor_ = std::move(previous.anchor_);
    has_anchor_ = std::move(previous.has_anchor_);
    anchored_ = std::move(previous.anchored_);
    anchor_.resize(n, V3::Zero());
    has_anchor_.resize(n, 0);
    anchored_.reserve(points_.size());
  }

  // Forces for the tool placed as `placed` (its one segment, or a
  // grasper's two jaws; radius R), penalty k N/m, with every point p at
  // rest[axis][p] + u[axis][p] (internal ids, the backend's streams); the
  // positions and box tests on up to `threads` threads. With `friction`
  // on, every touched point also gets anchor_friction's f_t (its anchor
  // kept in the tool's frame from substep to substep; a point that leaves
  // the contact drops its anchor).
  void evaluate(const std::array<const Real*, 3>& rest, const std::array<const Real*, 3>& u, const ToolPlacement& placed,
                Real k, const Friction& friction, int threads) {
    for (int32_t p : touched_) slot_[p] = -1;
    touched_.clear();
    force_.clear();
    const int jaws = placed.jaws;
    const V3 seg_a[2] = {placed.a.cast<Real>(), placed.a2.cast<Real>()};
    const V3 seg_b[2] = {placed.b.cast<Real>(), placed.b2.cast<Real>()};
    const Real radius = static_cast<Real>(placed.radius);
    const Real r2 = radius * radius;
    // A grasper's jaws close along -+ its jaw axis: the first (at +gap/2)
    // toward -axis. What a penalty presses along that is grip.
    const V3 jaw_axis = (placed.rotation * kJawAxis).cast<Real>();
    const V3 closing[2] = {-jaw_axis, jaw_axis};
    grip_ = 0;
    const int32_t npoint = static_cast<int32_t>(points_.size()), ntri = triangles();
    const int32_t* ta = corner_[0].data();
    const int32_t* tb = corner_[1].data();
    const int32_t* tc = corner_[2].data();
    const uint8_t* near = near_.data();
    // The broad phase's box holds every jaw's segment.
    Real lo[3], hi[3];
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis] = std::min(seg_a[0][axis], seg_b[0][axis]);
      hi[axis] = std::max(seg_a[0][axis], seg_b[0][axis]);
      for (int j = 1; j < jaws; ++j) {
        lo[axis] = std::min({lo[axis], seg_a[j][axis], seg_b[j][axis]});
        hi[axis] = std::max({hi[axis], seg_a[j][axis], seg_b[j][axis]});
      }
    }
    // Each thread its share of the points, then of the triangles (the loops
    // are functions of their own so that they vectorise as in a serial
    // build). One thread runs them outside a parallel region: libgomp
    // allocates a team for every region, even an inactive one, and a
    // haptic tick does not wait on the allocator.
    if (threads > 1) {
#pragma omp parallel num_threads(threads)
      {
        const int32_t n = omp_get_num_threads(), i = omp_get_thread_num();
        gather_positions(i * npoint / n, (i + 1) * npoint / n, rest, u);
#pragma omp barrier
        box_tests(i * ntri / n, (i + 1) * ntri / n, lo, hi, r2);
      }
    } else {
      gather_positions(0, npoint, rest, u);
      box_tests(0, ntri, lo, hi, r2);
    }
    // Each touching triangle's penalty w_j f to its corners; with the Hertz
    // layer, once the layer is solved over all of them (pending_).
    const auto spread = [&](const int32_t corner[3], const Real w[3], const V3& f) {
      for (int j = 0; j < 3; ++j) {
        const int32_t p = points_[corner[j]];
        if (slot_[p] < 0) {
          slot_[p] = static_cast<int32_t>(touched_.size());
          touched_.push_back(p);
          force_.insert(force_.end(), 3, Real(0));
        }
        Real* fp = &force_[3 * static_cast<size_t>(slot_[p])];
        for (int axis = 0; axis < 3; ++axis) fp[axis] += w[j] * f[axis];
      }
    };
    const bool layered = !layer_.empty();
    touches_.clear();
    sticks_.clear();
    // The stiffness the implicit integrator puts in its system (record_touches).
    const auto record = [&](const int32_t corner[3], const Real w[3], const V3& f, Real k_t) {
      const Real fn = f.norm();
      if (!record_ || !(fn > Real(0))) return;
      Touch t{{points_[corner[0]], points_[corner[1]], points_[corner[2]]}, {w[0], w[1], w[2]}, V3(f / fn), k_t};
      touches_.push_back(t);
    };
    if (layered) {
      hertz_.clear();
      pending_.clear();
    }
    for (int32_t word = 0; word < ntri; word += 8) {
      uint64_t any;
      std::memcpy(&any, near + word, sizeof any);
      if (any == 0) continue;
      for (int32_t i = word; i < word + 8; ++i) {
        if (!near[i]) continue;
        const int32_t corner[3] = {ta[i], tb[i], tc[i]};
        const Real share[3] = {share_[corner[0]], share_[corner[1]], share_[corner[2]]};
        for (int jaw = 0; jaw < jaws; ++jaw) {
          Pending t{{corner[0], corner[1], corner[2]}, {0, 0, 0}, V3::Zero()};
          if (!force_law::capsule_triangle_penalty(seg_a[jaw], seg_b[jaw], radius, at(corner[0]), at(corner[1]),
                                                   at(corner[2]), k, share, t.f, t.w))
            continue;
          if (jaws == 2) grip_ += t.f.dot(closing[jaw]);
          if (!layered) {
            spread(t.corner, t.w, t.f);
            record(t.corner, t.w, t.f, k * force_law::triangle_penalty_scale(share));
            continue;
          }
          const V3 q = t.w[0] * at(corner[0]) + t.w[1] * at(corner[1]) + t.w[2] * at(corner[2]);
          hertz_.add(t.f.data(), double(k * force_law::triangle_penalty_scale(share)), layer_[i].punch_radius,
                     layer_[i].e_star, double(force_law::segment_axial_position(q, seg_a[jaw], seg_b[jaw])));
          pending_.push_back(t);
        }
      }
    }
    if (layered) {
      hertz_.solve(placed.radius);
      for (size_t i = 0; i < pending_.size(); ++i) {
        const Real factor = static_cast<Real>(hertz_.factor(i));
        spread(pending_[i].corner, pending_[i].w, V3(factor * pending_[i].f));
        const int32_t* c = pending_[i].corner;
        const Real share[3] = {share_[c[0]], share_[c[1]], share_[c[2]]};
        record(c, pending_[i].w, pending_[i].f, factor * k * force_law::triangle_penalty_scale(share));
      }
    }
    if (friction.on()) add_friction(placed, k, friction);
  }

  // The contact's stiffness for the implicit integrator
  // (core/sim/implicit_system.h): with record on, evaluate() keeps every
  // touching penalty's corners (internal ids), weights, unit normal and
  // stiffness k_t (times its layer factor: the factor is held constant in
  // the linearisation), and every sticking point's friction spring (its
  // stick stiffness across the normal; a slipping point's force is bounded
  // by mu_k N and adds none).
  struct Touch {
    int32_t point[3];
    Real w[3];
    V3 n;
    Real k;
  };
  struct Stick {
    int32_t point;
    V3 n;
    Real k;
  };
  void record_touches(bool on) { record_ = on; }
  const std::vector<Touch>& touches() const { return touches_; }
  const std::vector<Stick>& sticks() const { return sticks_; }

  // A grasper's grip at the last evaluate: its jaws' penalties along their
  // closing directions, summed over both jaws, N (0 for one segment).
  Real grip() const { return grip_; }

 private:
  V3 at(int32_t local) const { return V3(x_[local], y_[local], z_[local]); }
  Eigen::Map<V3> force_at(size_t slot) { return Eigen::Map<V3>(&force_[3 * slot]); }

  // anchor_friction on every touched point, in the order of first touch
  // (each point's is its own: the order changes nothing but is fixed), its
  // stick spring k_t = k s_p; anchors of points no longer touched dropped.
  void add_friction(const ToolPlacement& placed, Real k, const Friction& friction) {
    const Eigen::Matrix<Real, 3, 3> R = placed.rotation.toRotationMatrix().cast<Real>();
    const V3 origin = placed.origin.cast<Real>();
    const Real mu_s = static_cast<Real>(friction.mu_s), mu_k = static_cast<Real>(friction.mu_k);
    for (size_t i = 0; i < touched_.size(); ++i) {
      const int32_t p = touched_[i];
      const V3 x = at(local_of_point_[p]);
      const V3 normal = force_at(i);
      V3 anchor = has_anchor_[p] ? V3(origin + R * anchor_[p]) : x;
      bool slipping = has_anchor_[p] == kSlipping;
      force_at(i) += force_law::anchor_friction(x, normal, k * point_scale_[p], mu_s, mu_k, anchor, slipping);
      const Real N = normal.norm();
      if (record_ && !slipping && N > Real(0)) sticks_.push_back({p, V3(normal / N), k * point_scale_[p]});
      anchor_[p] = R.transpose() * (anchor - origin);
      if (!has_anchor_[p]) anchored_.push_back(p);
      has_anchor_[p] = slipping ? kSlipping : kSticking;
    }
    size_t kept = 0;
    for (int32_t p : anchored_) {
      if (slot_[p] >= 0)
        anchored_[kept++] = p;
      else
        has_anchor_[p] = 0;
    }
    anchored_.resize(kept);
  }

 private:
  // Positions of surface points [begin, end) into x_, y_, z_.
  __attribute__((noinline)) void gather_positions(int32_t begin, int32_t end, const std::array<const Real*, 3>& rest,
                                                  const std::array<const Real*, 3>& u) {
    const int32_t* __restrict point = points_.data();
    const Real* __restrict RX = rest[0];
    const Real* __restrict RY = rest[1];
    const Real* __restrict RZ = rest[2];
    const Real* __restrict UX = u[0];
    const Real* __restrict UY = u[1];
    const Real* __restrict UZ = u[2];
    Real* __restrict X = x_.data();
    Real* __restrict Y = y_.data();
    Real* __restrict Z = z_.data();
#pragma omp simd
    for (int32_t i = begin; i < end; ++i) {
      const int32_t p = point[i];
      X[i] = RX[p] + UX[p], Y[i] = RY[p] + UY[p], Z[i] = RZ[p] + UZ[p];
    }
  }

  // Broad phase for triangles [begin, end), vectorised: whether the squared
  // distance from the segment's box [lo, hi] (the centre, for a sphere) to
  // each triangle's box is below r2.
  __attribute__((noinline)) void box_tests(int32_t begin, int32_t end, const Real lo[3], const Real hi[3], Real r2) {
    const int32_t* __restrict ta = corner_[0].data();
    const int32_t* __restrict tb = corner_[1].data();
    const int32_t* __restrict tc = corner_[2].data();
    uint8_t* __restrict near = near_.data();
    const Real* __restrict X = x_.data();
    const Real* __restrict Y = y_.data();
    const Real* __restrict Z = z_.data();
    const Real lx = lo[0], ly = lo[1], lz = lo[2], hx = hi[0], hy = hi[1], hz = hi[2];
#pragma omp simd
    for (int32_t t = begin; t < end; ++t) {
      // The gap between [plo, phi] and the triangle's extent along one axis.
      auto gap = [](Real plo, Real phi, Real u, Real v, Real w) {
        const Real mn = u < v ? (u < w ? u : w) : (v < w ? v : w), mx = u > v ? (u > w ? u : w) : (v > w ? v : w);
        return phi < mn ? mn - phi : plo > mx ? plo - mx : Real(0);
      };
      const Real gx = gap(lx, hx, X[ta[t]], X[tb[t]], X[tc[t]]);
      const Real gy = gap(ly, hy, Y[ta[t]], Y[tb[t]], Y[tc[t]]);
      const Real gz = gap(lz, hz, Z[ta[t]], Z[tb[t]], Z[tc[t]]);
      near[t] = gx * gx + gy * gy + gz * gz < r2;
    }
  }

 public:
  // Per point (lanes): index into force() or -1; 3 per touched point.
  const int32_t* slot() const { return slot_.data(); }
  const Real* force() const { return force_.data(); }
  int32_t touched() const { return static_cast<int32_t>(touched_.size()); }
  int32_t triangles() const { return static_cast<int32_t>(corner_[0].size()); }

 private:
  std::vector<int32_t> points_;          // surface points' internal ids, ascending
  std::vector<int32_t> local_of_point_;  // index into points_ or -1 (npoint)
  std::array<std::vector<int32_t>, 3> corner_;  // each triangle's corners as indices into points_, one array per corner
  std::vector<uint8_t> near_;            // per triangle: its box comes within the radius of the segment's box (8-byte words)
  std::vector<Real> share_;              // s_p / n_p per surface point (force_law::sphere_triangle_penalty)
  std::vector<TriangleLayer> layer_;     // per triangle with the Hertz layer on, else empty
  // With the layer: this substep's touching penalties, spread once it is solved.
  struct Pending {
    int32_t corner[3];
    Real w[3];
    V3 f;
  };
  std::vector<Pending> pending_;
  force_law::HertzLayer hertz_;
  std::vector<Real> x_, y_, z_;          // surface points' positions this substep
  std::vector<int32_t> slot_;            // per lane
  std::vector<Real> force_;              // per touched point, 3 each
  std::vector<int32_t> touched_;         // touched points in order of first touch
  Real grip_ = 0;                        // a grasper's jaws' closing forces, summed, N
  std::vector<Real> point_scale_;        // s_p per point (npoint)
  std::vector<V3> anchor_;               // friction: each point's anchor in the tool's frame, m (npoint)
  static constexpr uint8_t kSticking = 1, kSlipping = 2;
  std::vector<uint8_t> has_anchor_;      // 0 none, kSticking or kSlipping (npoint)
  bool record_ = false;                  // record_touches
  std::vector<Touch> touches_;
  std::vector<Stick> sticks_;
  std::vector<int32_t> anchored_;        // points with an anchor
};

}  // namespace organsim
