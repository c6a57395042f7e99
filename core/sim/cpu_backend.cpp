#include "core/sim/cpu_backend.h"

#include <omp.h>

#include <algorithm>
#include <fstream>
#include <string>

#include "core/util/error.h"

namespace organsim {

namespace {

std::string cpu_model_name() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

enum ToolKind { kNoTool = 0, kPush = 1, kPull = 2 };

// Threads pay off only when each has a few thousand points: below that the
// per-step fork/join costs more than it saves (and thrashes a loaded machine).
int choose_threads(const Model& model, const CpuBackendOptions& options) {
  if (options.threads > 0) return options.threads;
  return model.npoint() >= 4096 ? omp_get_max_threads() : 1;
}


// Step-invariant inputs of one substep.
template <class Real>
struct StepContext {
  Real dt, inv_dt, dt2, drag;  // drag = 1 - alpha dt
  Eigen::Matrix<Real, 3, 1> gravity, tool_center;
  Real tool_radius, tool_k;
};

template <class Real>
class CpuBackend final : public Backend {
  using V3 = Eigen::Matrix<Real, 3, 1>;

 public:
  CpuBackend(const Model& model, const BackendTool& tool, const CpuBackendOptions& options)
      : model_(model), tool_(tool), threads_(choose_threads(model, options)) {
    const int32_t n = model.npoint();
    const auto& layout = model.layout;
    // State is the displacement u = x - X from rest: in float, x itself
    // would round away the per-step increment dt^2 F/m (~1e-9 m against a
    // 4e-9 m spacing of floats near 5 cm); u starts at 0 where floats are fine.
    rest_.resize(n);
    for (int32_t i = 0; i < n; ++i) rest_[i] = model.rest_position[i].cast<Real>();
    u_.assign(n, V3::Zero());
    u_prev_ = u_;
    u_next_ = u_;
    // Per-entry copies of the spring and tet parameters in the backend's
    // precision, so the gather reads one contiguous stream per slot. Rest
    // lengths and volumes are recomputed from the rounded rest positions
    // exactly as the gather computes them, so the rest state is force-free.
    spring_rest_.resize(layout.springs.item.size(), 0);
    spring_k_.resize(layout.springs.item.size(), 0);
    spring_d_.resize(layout.springs.item.size(), 0);
    for (size_t e = 0; e < layout.springs.item.size(); ++e) {
      const int32_t s = layout.springs.item[e];
      if (s < 0) continue;
      const int32_t p = point_of_entry(layout.springs, layout.chunk_size, static_cast<int32_t>(e));
      spring_rest_[e] = (rest_[layout.spring_other[e]] - rest_[p]).norm();
      spring_k_[e] = static_cast<Real>(model.spring_k[s]);
      spring_d_[e] = static_cast<Real>(model.spring_d[s]);
    }
    if (model.has_volume()) {
      tet_rest_.resize(layout.tets.item.size(), 0);
      tet_k_.resize(layout.tets.item.size(), 0);
      for (size_t e = 0; e < layout.tets.item.size(); ++e) {
        const int32_t t = layout.tets.item[e];
        if (t < 0) continue;
        const int32_t p = point_of_entry(layout.tets, layout.chunk_size, static_cast<int32_t>(e));
        const auto& o = layout.tet_others[e];
        const V3 a = rest_[o[0]] - rest_[p], b = rest_[o[1]] - rest_[p], c = rest_[o[2]] - rest_[p];
        tet_rest_[e] = a.dot(b.cross(c)) / Real(6);
        tet_k_[e] = static_cast<Real>(model.tet_k[t]);
      }
    }
    mass_.resize(n);
    inv_mass_.resize(n);
    for (int32_t i = 0; i < n; ++i) {
      mass_[i] = static_cast<Real>(model.mass[i]);
      inv_mass_[i] = static_cast<Real>(model.inv_mass[i]);
    }
    attached_.assign(n, -1);
    partial_.resize(layout.nchunk);
    device_ = cpu_model_name() + ", " + std::to_string(threads_) + " thread" + (threads_ > 1 ? "s" : "");
  }

  std::string name() const override { return "cpu"; }
  std::string device() const override { return device_; }
  std::string precision() const override { return sizeof(Real) == 8 ? "double" : "float"; }
  int32_t reaction_latency_ticks() const override { return 0; }
  double time() const override { return time_; }

  Plan plan() const override {
    Plan plan;
    const auto& m = model_;
    const size_t real = sizeof(Real);
    plan.passes.push_back({"springs", std::to_string(m.nspring()) + " springs gathered from both ends (" +
                                          std::to_string(m.layout.springs.item.size()) + " slots)"});
    if (m.has_volume())
      plan.passes.push_back({"volume", std::to_string(m.ntet()) + " tets gathered per vertex (" +
                                           std::to_string(m.layout.tets.item.size()) + " slots)"});
    if (m.has_gravity()) plan.passes.push_back({"gravity", "m g on every free point"});
    if (tool_.present)
      plan.passes.push_back({"tool-contact", tool_.mode == ToolMode::Push ? "sphere penalty contact"
                                                                          : "grasp attachment springs"});
    plan.passes.push_back({"integrate", "position Verlet, fused with the gathers above"});
    const size_t n = static_cast<size_t>(m.npoint());
    plan.buffers.push_back({"x_t, x_{t-1}, x_{t+1}", 3 * n * 3 * real});
    plan.buffers.push_back({"mass, 1/mass", 2 * n * real});
    plan.buffers.push_back({"spring slots (other, rest, k, d)",
                            m.layout.springs.item.size() * (sizeof(int32_t) + 3 * real)});
    if (m.has_volume())
      plan.buffers.push_back({"tet slots (3 others, rest volume, k_v)",
                              m.layout.tets.item.size() * (3 * sizeof(int32_t) + 2 * real)});
    if (tool_.present) plan.buffers.push_back({"tool partial sums per chunk", partial_.size() * sizeof(Partial)});
    plan.dispatches_per_step = 1;
    plan.syncs_per_step = 0;
    return plan;
  }

  void attach(const Attachment& attachment) override {
    release();
    attach_offset_.assign(attachment.points.size(), V3::Zero());
    for (size_t k = 0; k < attachment.points.size(); ++k) {
      attached_[attachment.points[k]] = static_cast<int32_t>(k);
      attach_offset_[k] = attachment.offsets[k].cast<Real>();
    }
    attached_points_ = attachment.points;
  }

  void release() override {
    for (int32_t p : attached_points_) attached_[p] = -1;
    attached_points_.clear();
  }

  void positions(std::vector<Vec3>& out) const override {
    out.resize(u_.size());
    for (size_t i = 0; i < u_.size(); ++i) out[i] = model_.rest_position[i] + u_[i].template cast<double>();
  }

  void set_state(const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev) override {
    if (x.size() != u_.size() || x_prev.size() != u_.size())
      throw Error(ErrorKind::Input, "set_state: expected " + std::to_string(u_.size()) + " positions");
    for (size_t i = 0; i < u_.size(); ++i) {
      u_[i] = (x[i] - model_.rest_position[i]).cast<Real>();
      u_prev_[i] = (x_prev[i] - model_.rest_position[i]).cast<Real>();
    }
  }

  Reaction tick(const TickRequest& request) override {
    StepContext<Real> ctx;
    ctx.dt = static_cast<Real>(request.dt);
    ctx.inv_dt = static_cast<Real>(1.0 / request.dt);
    ctx.dt2 = static_cast<Real>(request.dt * request.dt);
    ctx.drag = static_cast<Real>(1.0 - model_.viscous_damping * request.dt);
    ctx.gravity = model_.gravity.cast<Real>();
    ctx.tool_radius = static_cast<Real>(tool_.radius);
    ctx.tool_k = static_cast<Real>(tool_.contact_stiffness);
    const int tool_kind = !(tool_.present && request.tool_active) ? kNoTool
                          : tool_.mode == ToolMode::Push         ? kPush
                                                                 : kPull;
    Reaction reaction;
    for (int32_t s = 0; s < request.substeps; ++s) {
      // The force of substep s acts at its start: tool centre interpolated there.
      const double f = static_cast<double>(s) / request.substeps;
      ctx.tool_center = (request.tool_from + f * (request.tool_to - request.tool_from)).cast<Real>();
      reaction = step(ctx, tool_kind);
      time_ += request.dt;
    }
    return reaction;
  }

 private:
  struct Partial {
    V3 force, torque;
    int32_t contacts;
  };

  Reaction step(const StepContext<Real>& ctx, int tool_kind) {
    const bool volume = model_.has_volume(), gravity = model_.has_gravity();
    // Lean scenes: each combination of passes is its own compiled loop, so a
    // scene without volume or tool never touches that code or data.
    if (volume) {
      if (gravity) return dispatch_tool<true, true>(ctx, tool_kind);
      return dispatch_tool<true, false>(ctx, tool_kind);
    }
    if (gravity) return dispatch_tool<false, true>(ctx, tool_kind);
    return dispatch_tool<false, false>(ctx, tool_kind);
  }

  template <bool Volume, bool Gravity>
  Reaction dispatch_tool(const StepContext<Real>& ctx, int tool_kind) {
    switch (tool_kind) {
      case kPush: return run<Volume, Gravity, kPush>(ctx);
      case kPull: return run<Volume, Gravity, kPull>(ctx);
      default: return run<Volume, Gravity, kNoTool>(ctx);
    }
  }

  template <bool Volume, bool Gravity, int Tool>
  Reaction run(const StepContext<Real>& ctx) {
    const int32_t nchunk = model_.layout.nchunk;
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (int32_t c = 0; c < nchunk; ++c) chunk<Volume, Gravity, Tool>(ctx, c);
    std::swap(u_prev_, u_);  // u_{t-1} <- u_t
    std::swap(u_, u_next_);  // u_t <- u_{t+1}
    Reaction reaction;
    if constexpr (Tool != kNoTool) {
      // Fixed-order sum of per-chunk partials: identical for any thread count.
      V3 force = V3::Zero(), torque = V3::Zero();
      for (const Partial& p : partial_) {
        force += p.force;
        torque += p.torque;
        reaction.contacts += p.contacts;
      }
      reaction.force = force.template cast<double>();
      reaction.torque = torque.template cast<double>();
    }
    return reaction;
  }

  template <bool Volume, bool Gravity, int Tool>
  void chunk(const StepContext<Real>& ctx, int32_t c) {
    const auto& L = model_.layout;
    const int32_t C = L.chunk_size;
    const int32_t begin = c * C, end = std::min(model_.npoint(), begin + C);
    Partial partial{V3::Zero(), V3::Zero(), 0};
    for (int32_t p = begin; p < end; ++p) {
      const int32_t lane = p - begin;
      const V3 Xi = rest_[p], ui = u_[p];
      const V3 vi = (ui - u_prev_[p]) * ctx.inv_dt;
      V3 f = V3::Zero();

      const int32_t* other = L.spring_other.data() + L.springs.chunk_offset[c] + lane;
      const int32_t nspring = L.springs.count[p];
      const int32_t base = L.springs.chunk_offset[c] + lane;
      for (int32_t j = 0; j < nspring; ++j) {
        const int32_t e = base + j * C;
        const int32_t q = other[j * C];
        const V3 l = (rest_[q] - Xi) + (u_[q] - ui);
        const Real length = l.norm();
        if (length <= Real(0)) continue;  // coincident points: no direction, no force
        const V3 dir = l / length;
        const V3 dv = (u_[q] - u_prev_[q]) * ctx.inv_dt - vi;
        f += (spring_k_[e] * (length - spring_rest_[e]) + spring_d_[e] * dv.dot(dir)) * dir;
      }

      if constexpr (Volume) {
        const int32_t tbase = L.tets.chunk_offset[c] + lane;
        for (int32_t j = 0; j < L.tets.count[p]; ++j) {
          const int32_t e = tbase + j * C;
          const auto& o = L.tet_others[e];
          const V3 a = (rest_[o[0]] - Xi) + (u_[o[0]] - ui);
          const V3 b = (rest_[o[1]] - Xi) + (u_[o[1]] - ui);
          const V3 cc = (rest_[o[2]] - Xi) + (u_[o[2]] - ui);
          const Real v = a.dot(b.cross(cc)) / Real(6);
          // dV/dx_p for V = (a-p).((b-p)x(c-p))/6 is (c-a)x(b-a)/6.
          const V3 grad = (cc - a).cross(b - a) / Real(6);
          f += tet_k_[e] * (tet_rest_[e] - v) * grad;
        }
      }
      if constexpr (Gravity) f += mass_[p] * ctx.gravity;

      [[maybe_unused]] const V3 xi = Xi + ui;
      if constexpr (Tool == kPush) {
        const V3 d = xi - ctx.tool_center;
        const Real dist = d.norm();
        if (dist < ctx.tool_radius) {
          const V3 n = dist > Real(0) ? V3(d / dist) : V3(0, 0, 1);
          const V3 fc = ctx.tool_k * (ctx.tool_radius - dist) * n;
          f += fc;
          partial.force -= fc;
          partial.torque += d.cross(-fc);
          ++partial.contacts;
        }
      } else if constexpr (Tool == kPull) {
        const int32_t k = attached_[p];
        if (k >= 0) {
          const V3 fc = ctx.tool_k * (ctx.tool_center + attach_offset_[k] - xi);
          f += fc;
          partial.force -= fc;
          partial.torque += (xi - ctx.tool_center).cross(-fc);
          ++partial.contacts;
        }
      }

      // Position Verlet with mass-proportional drag; fixed points have 1/m = 0
      // and no velocity, so they stay put.
      u_next_[p] = inv_mass_[p] > Real(0) ? V3(ui + ctx.drag * (ui - u_prev_[p]) + ctx.dt2 * inv_mass_[p] * f) : ui;
    }
    if constexpr (Tool != kNoTool) partial_[c] = partial;
  }

  const Model& model_;
  BackendTool tool_;
  int threads_;
  std::string device_;
  double time_ = 0;
  std::vector<V3> rest_;                // X, rest positions (npoint)
  std::vector<V3> u_, u_prev_, u_next_;  // displacements at t, t-1, t+1 (npoint)
  std::vector<Real> spring_rest_, spring_k_, spring_d_;  // per slot (nentry)
  std::vector<Real> tet_rest_, tet_k_;                   // per slot (nentry), empty without volume
  std::vector<Real> mass_, inv_mass_;
  std::vector<int32_t> attached_;  // attachment index per point or -1 (npoint)
  std::vector<int32_t> attached_points_;
  std::vector<V3> attach_offset_;
  std::vector<Partial> partial_;   // tool reaction per chunk (nchunk)
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend(const Model& model, const BackendTool& tool,
                                          const CpuBackendOptions& options) {
  if (options.precision == Precision::Float) return std::make_unique<CpuBackend<float>>(model, tool, options);
  return std::make_unique<CpuBackend<double>>(model, tool, options);
}

}  // namespace organsim
