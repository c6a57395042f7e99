#include "core/sim/cpu_backend.h"
#include "core/sim/contact_plan.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <utility>

#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/kernel_inputs.h"
#include "core/sim/step_plan.h"
#include "core/sim/surface_contact.h"
#include "core/sim/thread_choice.h"
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

// What the springs pass does with sutures, if the model has any.
std::string sutures_detail(const Model& m) {
  if (m.nsuture() == 0) return "";
  return ", " + std::to_string(m.nsuture()) + " of them sutures (tension only, rest length refreshed per tick)";
}

// Three coordinate arrays (structure of arrays): the rest positions the
// surface pass reads, and the state kept across a rebuild.
template <class Real>
struct Soa3 {
  std::vector<Real> x, y, z;
  void assign(size_t n, Real v) {
    x.assign(n, v);
    y.assign(n, v);
    z.assign(n, v);
  }
  void resize(size_t n, Real v) {
    x.resize(n, v);
    y.resize(n, v);
    z.resize(n, v);
  }
  void copy(size_t from, size_t to) {
    x[to] = x[from];
    y[to] = y[from];
    z[to] = z[from];
  }
};

// Everything a CpuBackend derives from one Model version, in its precision:
// packed off the tick's path by prepare() and swapped in by adopt() with
// one move.
template <class Real>
struct CpuTables {
  const Model* model = nullptr;  // the version they were packed from
  StepPlan plan;                 // the passes of its step
  std::unique_ptr<SimdKernel<Real>> kernel;  // its packed streams and, while it runs, the state
  std::vector<ChunkReaction> partial;        // the tool reaction per chunk
  Soa3<Real> rest;                           // X, rest positions (npoint)
  std::vector<std::pair<int32_t, int32_t>> suture_slots;  // (layout slot, spring) of every suture's slot
  std::vector<Real> tool_scale;  // tool stiffness multiplier per point, Model::tool_k_scale (npad, 0 for padding)
  SurfaceContact<Real> surface;  // the surface-contact pass (a pushing tool on the surface)
};

// What CpuBackend::prepare hands to adopt.
template <class Real>
struct CpuPrepared final : PreparedModel {
  explicit CpuPrepared(const Model& next) : PreparedModel(next) {}
  CpuTables<Real> tables;
};

template <class Real>
class CpuBackend final : public Backend {
  using Tables = CpuTables<Real>;

 public:
  CpuBackend(const Model& model, const BackendTool& tool, const CpuBackendOptions& options, StepTiming timing)
      : tool_(tool),
        simd_target_(options.simd.empty() ? default_simd_target() : simd_target_named(options.simd, "cpu backend")),
        threads_(options.threads > 0 ? options.threads : 1), timing_(std::move(timing)) {
    // State is the displacement u = x - X from rest and the last step's
    // increment d = u_t - u_{t-1}. In float, x itself would round away the
    // per-step increment dt^2 F/m (~1e-9 m against a 4e-9 m spacing of floats
    // near 5 cm), and u_{t-1} would leave the velocity d/dt as the difference
    // of two nearly equal numbers, worse the smaller dt is. In exact
    // arithmetic this is the same position Verlet.
    const size_t n = static_cast<size_t>(model.npoint());
    u_.assign(n, 0);
    d_.assign(n, 0);
    attached_.assign(n, -1);
    t_ = pack(model);
    install();
    std::string how;
    if (options.threads <= 0 && omp_get_max_threads() > 1) {
      if (options.live_share > 0) {
        // A live loop: all but one (or one, for a model too small to gain
        // from them) while that keeps up with the clock, all when it does
        // not (thread_choice.h); the ticks themselves tell.
        const int all = omp_get_max_threads();
        if (all - 1 > 1) how = choose_threads_by_timing(all - 1);
        else threads_ = 1;
        live_share_ = options.live_share;
        choice_.emplace(threads_, all);
        char buf[96];
        std::snprintf(buf, sizeof buf, " (live: %d while a step takes over %.2g dt on %d)", all, live_share_, threads_);
        how += buf;
      } else {
        how = choose_threads_by_timing(omp_get_max_threads());
        choice_.emplace(threads_, threads_ == 1 ? omp_get_max_threads() : 1);
      }
    }
    device_ = cpu_model_name() + ", " + threads_text(threads_) + how;
  }

  std::unique_ptr<PreparedModel> prepare(const Model& next) const override {
    auto prepared = std::make_unique<CpuPrepared<Real>>(next);
    prepared->tables = pack(next);
    return prepared;
  }

  void adopt(std::unique_ptr<PreparedModel> prepared) override {
    auto* p = dynamic_cast<CpuPrepared<Real>*>(prepared.get());
    if (!p) throw Error(ErrorKind::Backend, "cpu backend: adopt() of a version it did not prepare");
    const Model& next = p->model();
    const size_t old_n = u_.x.size(), n = static_cast<size_t>(next.npoint());
    if (n < old_n || next.origin.size() != n)
      throw Error(ErrorKind::Backend, "cpu backend: rebuild from a Model with " + std::to_string(n) +
                                          " points after " + std::to_string(old_n) + " (points are append-only)");
    pull_state();
    // An appended point copies its origin's displacement and increment: its
    // rest position is the origin's, so it starts at the same x_t and x_{t-1}.
    for (Soa3<Real>* s : {&u_, &d_}) {
      s->resize(n, 0);
      for (size_t i = old_n; i < n; ++i) s->copy(next.origin[i], i);
    }
    attached_.resize(n, -1);
    // The previous version's tables leave with `prepared`; friction's
    // anchors stay (ids are kept), so a grip holds through a cut.
    std::swap(t_, p->tables);
    t_.surface.take_anchors(p->tables.surface);
    install();
  }

  std::string name() const override { return "cpu"; }
  // The kernel as of now (a rebuild repacks it for the new model).
  // With the thread count chosen by timing, also what the re-timing during the run did.
  std::string device() const override {
    std::string retimed;
    if (choice_ && choice_->probes() > 0) {
      retimed = ", re-timed during the run: " + std::to_string(choice_->probes()) + " probe step" +
                (choice_->probes() > 1 ? "s" : "") + ", " + std::to_string(choice_->switches()) + " switch" +
                (choice_->switches() == 1 ? "" : "es") + ", now " + threads_text(choice_->chosen());
    }
    return device_ + retimed + ", " + kernel_name() + " kernel";
  }
  std::string precision() const override { return sizeof(Real) == 8 ? "double" : "float"; }
  // "simd (avx2)", "simd (sse4)", ...
  std::string kernel_name() const { return "simd (" + t_.kernel->target().name + ")"; }
  int32_t reaction_latency_ticks() const override { return 0; }
  double time() const override { return time_; }

  const StepPlan& step_plan() const override { return t_.plan; }

  Plan plan() const override {
    Plan plan;
    for (Pass pass : t_.plan.passes) plan.passes.push_back({pass_name(pass), pass_detail(pass)});
    if (t_.plan.sutures > 0)
      plan.per_tick.push_back({"suture-rest", std::to_string(t_.plan.sutures) + " sutures' rest lengths from their schedule"});
    plan.buffers.push_back({kernel_name() + " kernel: point records, state, spring slots, tet batches, tet force slices",
                            t_.kernel->bytes()});
    if (t_.plan.tool != ToolTerm::None)
      plan.buffers.push_back({"tool partial sums per chunk", t_.partial.size() * sizeof(ChunkReaction)});
    plan.dispatches_per_step = 1;
    plan.syncs_per_step = 0;
    return plan;
  }

  // What this backend's kernel does for one pass of the step plan.
  std::string pass_detail(Pass pass) const {
    const auto& m = *t_.model;
    const int32_t nlanes = t_.kernel->lanes();
    const std::string lanes = std::to_string(nlanes) + " " + precision() + " lanes";
    const std::string kernel = " (" + kernel_name() + " kernel)";
    switch (pass) {
      case Pass::NodalPressure:
        return std::to_string(m.ntet()) + " tets' 6 V_t read in pairs that share a face, " + std::to_string(nlanes) +
               " pairs per batch (2 fixed slices), a barrier, each point's nodal volume and pressure, a barrier" +
               kernel;
      case Pass::ShearSmoothing:
        return "every point's stress on its node-averaged deformation gradient, gathered over its spring slots, then "
               "a barrier" + kernel;
      case Pass::Springs:
        return std::to_string(m.nspring()) + " springs gathered from both ends (" +
               std::to_string(m.layout.springs.item.size()) + " slots)" + sutures_detail(m);
      case Pass::Volume:
        return std::to_string(m.ntet()) + " tets evaluated once, " + std::to_string(nlanes) +
               " per batch, into 2 fixed force slices" + kernel;
      case Pass::ShearElement:
        return std::string(t_.plan.element == ElementTerm::SmoothedShear ? "smoothed " : "") +
               "shear element (neo-Hookean, no lambda" + (m.shear_damping_time > 0 ? ", with its damper" : "") + "), " +
               std::to_string(m.ntet()) + " tets in pairs that share a face, " + std::to_string(nlanes) +
               " pairs per batch, into 2 fixed force slices" + kernel;
      case Pass::Gravity: return "m g on every free point";
      case Pass::SurfaceContact:
        return std::string(shape_name(tool_.shape)) + " against " + std::to_string(m.nsurface()) +
               " surface triangles, broad phase: the " + shape_name(tool_.shape) +
               " against each triangle's box; each touching "
               "triangle's penalty at its closest point, spread to its corners (box tests on the step's threads, "
               "penalties on one thread in triangle order)" + hertz_layer_plan(tool_) + friction_plan(tool_);
      case Pass::ToolContact:
        return t_.plan.tool == ToolTerm::Push      ? std::string(shape_name(tool_.shape)) + " penalty contact on the points"
               : t_.plan.tool == ToolTerm::Surface ? "the surface contact's forces on the touched points"
                                                   : "grasp attachment springs";
      case Pass::Integrate:
        return "position Verlet with drag, fused with the force passes (" + lanes + ", " + kernel_name() +
               " kernel)";
      // Implicit integration runs on the reference backend (reference_backend.h), never in this one's plan.
      case Pass::Linearise:
      case Pass::ConjugateGradient:
      case Pass::VelocityUpdate: break;
    }
    return "";
  }

  void attach(const Attachment& attachment) override {
    release();
    attach_offset_.clear();
    for (size_t k = 0; k < attachment.points.size(); ++k) {
      attached_[attachment.points[k]] = static_cast<int32_t>(k);
      for (int j = 0; j < 3; ++j) attach_offset_.push_back(static_cast<Real>(attachment.offsets[k][j]));
    }
    attached_points_ = attachment.points;
  }

  void release() override {
    for (int32_t p : attached_points_) attached_[p] = -1;
    attached_points_.clear();
  }

  void positions(std::vector<Vec3>& out) const override {
    out.resize(u_.x.size());
    const Real *ux = t_.kernel->displacement(0), *uy = t_.kernel->displacement(1), *uz = t_.kernel->displacement(2);
    for (size_t i = 0; i < out.size(); ++i) out[i] = t_.model->rest_position[i] + Vec3(ux[i], uy[i], uz[i]);
  }

  void set_state(const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev) override {
    if (x.size() != u_.x.size() || x_prev.size() != u_.x.size())
      throw Error(ErrorKind::Input, "set_state: expected " + std::to_string(u_.x.size()) + " positions");
    for (size_t i = 0; i < x.size(); ++i) {
      const Vec3 u = x[i] - t_.model->rest_position[i], d = x[i] - x_prev[i];
      u_.x[i] = static_cast<Real>(u.x());
      u_.y[i] = static_cast<Real>(u.y());
      u_.z[i] = static_cast<Real>(u.z());
      d_.x[i] = static_cast<Real>(d.x());
      d_.y[i] = static_cast<Real>(d.y());
      d_.z[i] = static_cast<Real>(d.z());
    }
    push_state();
  }

  Reaction tick(const TickRequest& request) override {
    KernelStepInputs<Real> ctx;
    ctx.dt = static_cast<Real>(request.dt);
    ctx.inv_dt = static_cast<Real>(1.0 / request.dt);
    ctx.dt2 = static_cast<Real>(request.dt * request.dt);
    ctx.drag = static_cast<Real>(1.0 - t_.model->viscous_damping * request.dt);
    ctx.shear_damping = static_cast<Real>(t_.model->shear_damping_time / request.dt);
    for (int k = 0; k < 3; ++k) ctx.gravity[k] = static_cast<Real>(t_.model->gravity[k]);
    ctx.tool_radius = static_cast<Real>(tool_.radius);
    ctx.tool_k = static_cast<Real>(tool_.contact_stiffness);
    ctx.tool = request.tool_active ? t_.plan.tool : ToolTerm::None;
    ctx.attached = attached_.data();
    ctx.attach_offset = attach_offset_.data();
    ctx.tool_scale = t_.tool_scale.data();
    refresh_suture_rest();
    Reaction reaction;
    auto substep = [&](int32_t s) {
      // The force of substep s acts at its start: the tool's pose interpolated there.
      const ToolPlacement placed = request.tool_at(tool_, s);
      for (int k = 0; k < 3; ++k) {
        ctx.tool_center[k] = static_cast<Real>(placed.origin[k]);
        ctx.tool_a[k] = static_cast<Real>(placed.a[k]);
        ctx.tool_b[k] = static_cast<Real>(placed.b[k]);
      }
      ctx.tool_reach = static_cast<Real>(placed.reach());
      if (ctx.tool == ToolTerm::Surface) surface_contact(ctx, placed);
      reaction = step(ctx);
      if (ctx.tool == ToolTerm::Surface) reaction.grip = static_cast<double>(t_.surface.grip());
      time_ += request.dt;
    };
    if (!choice_) {
      for (int32_t s = 0; s < request.substeps; ++s) substep(s);
      return reaction;
    }
    // Thread count chosen by timing: keep timing (thread_choice.h).
    if (live_share_ > 0) choice_->set_budget(live_share_ * request.dt);
    int32_t first = 0;
    if (choice_->probe_due() && request.substeps > 0) {
      threads_ = choice_->other();
      choice_->record_probe(timed(1, [&] { substep(first++); }));
    }
    threads_ = choice_->chosen();
    choice_->record_tick(request.substeps - first, timed(request.substeps - first, [&] {
                           for (int32_t s = first; s < request.substeps; ++s) substep(s);
                         }));
    return reaction;
  }

 private:
  // Everything derived from `model` in the backend's precision; the
  // constructor and prepare() share it, so a topology change needs no code
  // of its own here. Reads nothing of the run (state, time, thread count):
  // prepare() runs it on another thread while the backend ticks. A model
  // the kernel cannot run is an Error(Backend) naming why.
  Tables pack(const Model& model) const {
    Tables t;
    t.model = &model;
    t.plan = make_step_plan(model, tool_);
    const std::string refusal = simd_kernel_unsupported(t.plan, model.layout.chunk_size, simd_target_);
    if (!refusal.empty())
      throw Error(ErrorKind::Backend, "cpu backend: the simd kernel (" + simd_target_.name +
                                          ") cannot run this model: " + refusal);
    t.kernel = make_simd_kernel<Real>(simd_target_);
    t.kernel->pack(model, t.plan);
    t.partial.resize(t.kernel->nchunk());
    const int32_t n = model.npoint();
    t.rest.assign(n, 0);
    for (int32_t i = 0; i < n; ++i) {
      t.rest.x[i] = static_cast<Real>(model.rest_position[i].x());
      t.rest.y[i] = static_cast<Real>(model.rest_position[i].y());
      t.rest.z[i] = static_cast<Real>(model.rest_position[i].z());
    }
    // Padding lanes (at the origin, no mass) may fall inside a push tool: scale 0.
    t.tool_scale.assign(npad_of(t), 0);
    for (int32_t i = 0; i < n; ++i) t.tool_scale[i] = static_cast<Real>(model.tool_scale(i));
    // The slots of sutures, whose rest lengths follow their schedule (refresh_suture_rest).
    const auto& springs = model.layout.springs;
    for (int32_t e = 0; e < static_cast<int32_t>(springs.item.size()); ++e)
      if (springs.item[e] >= model.first_suture()) t.suture_slots.push_back({e, springs.item[e]});
    if (t.plan.tool == ToolTerm::Surface) t.surface.pack(model, t.tool_scale, t.tool_scale.size(), tool_.hertz_layer);
    return t;
  }

  // The surface-contact pass at this substep's positions (X + u): the
  // kernel's tool pass then adds its per-point forces.
  void surface_contact(KernelStepInputs<Real>& ctx, const ToolPlacement& placed) {
    t_.surface.evaluate({t_.rest.x.data(), t_.rest.y.data(), t_.rest.z.data()},
                        {t_.kernel->displacement(0), t_.kernel->displacement(1), t_.kernel->displacement(2)}, placed,
                        ctx.tool_k, tool_.friction, threads_);
    ctx.contact_slot = t_.surface.slot();
    ctx.contact_force = t_.surface.force();
  }

  // Sutures tighten on their schedule: rest lengths at the start of the tick,
  // constant over its substeps. The few suture slots only; nothing allocates.
  void refresh_suture_rest() {
    for (const auto& [e, s] : t_.suture_slots)
      t_.kernel->set_spring_rest(e, static_cast<Real>(t_.model->spring_rest_at(s, time_)));
  }

  // Points the kernel reads a register at a time, padding included.
  static size_t npad_of(const Tables& t) {
    return static_cast<size_t>(t.kernel->nchunk()) * t.model->layout.chunk_size;
  }
  // Makes t_ (just packed) the tables the backend steps: the state u_, d_
  // (npoint of t_.model) into its kernel, the sutures' rest lengths at time_.
  void install() {
    // The kernel reads attachment indices a register of points at a time, padding included.
    attached_.resize(std::max(attached_.size(), npad_of(t_)), -1);
    refresh_suture_rest();
    push_state();
  }
  // The kernel holds the state while it runs; u_, d_ hold it across a rebuild.
  void push_state() {
    for (size_t i = 0; i < u_.x.size(); ++i) {
      const Real u[3] = {u_.x[i], u_.y[i], u_.z[i]}, d[3] = {d_.x[i], d_.y[i], d_.z[i]};
      t_.kernel->set_point(static_cast<int32_t>(i), u, d);
    }
  }
  void pull_state() {
    Real u[3], d[3];
    for (size_t i = 0; i < u_.x.size(); ++i) {
      t_.kernel->get_point(static_cast<int32_t>(i), u, d);
      u_.x[i] = u[0], u_.y[i] = u[1], u_.z[i] = u[2];
      d_.x[i] = d[0], d_.y[i] = d[1], d_.z[i] = d[2];
    }
  }

  Reaction step(const KernelStepInputs<Real>& in) {
    t_.kernel->step(in, threads_, t_.partial);
    Reaction reaction;
    if (in.tool != ToolTerm::None) {
      // Fixed-order sum of per-chunk partials: identical for any thread count.
      for (const ChunkReaction& p : t_.partial) {
        reaction.force += p.force;
        reaction.torque += p.torque;
        reaction.contacts += p.contacts;
      }
    }
    return reaction;
  }

  // Times steps from rest on 1 thread and on `all` (the hardware threads,
  // or all but one in a live loop) (alternating, best of five each, at least ~2 ms of steps per timing so
  // that a liver-size model is timed over several steps, not one) and keeps
  // the faster; the state is put back to rest afterwards. Small models stay
  // on one thread when the fork/join costs more than it saves. Returns what
  // it measured, for device().
  std::string choose_threads_by_timing(int all) {
    KernelStepInputs<Real> ctx{};
    ctx.dt = Real(1e-6), ctx.inv_dt = Real(1e6), ctx.dt2 = Real(1e-12), ctx.drag = Real(1);
    ctx.shear_damping = static_cast<Real>(t_.model->shear_damping_time * 1e6);
    auto time_steps = [&](int threads, int32_t steps) {
      threads_ = threads;
      return 1e3 * timed(steps, [&] {
               for (int32_t s = 0; s < steps; ++s) step(ctx);
             }) / steps;
    };
    // Warm-up: the first parallel step also starts the thread pool.
    time_steps(all, 1);
    const double estimate = time_steps(1, 1);
    const int32_t steps = std::clamp(static_cast<int32_t>(2.0 / std::max(estimate, 1e-4)), 4, 200);
    double best[2] = {1e30, 1e30};
    for (int round = 0; round < 5; ++round)
      for (int which = 0; which < 2; ++which) best[which] = std::min(best[which], time_steps(which ? all : 1, steps));
    threads_ = best[1] < best[0] ? all : 1;
    u_.assign(u_.x.size(), 0);
    d_.assign(d_.x.size(), 0);
    push_state();
    char buf[96];
    std::snprintf(buf, sizeof buf, " (timed: %.4f ms per step on 1, %.4f on %d)", best[0], best[1], all);
    return buf;
  }

  // Seconds that run() of `steps` steps on threads_ threads took, as the
  // thread choice sees them (timing_ may stand in for the clock).
  template <class F>
  double timed(int32_t steps, F run) {
    const auto start = std::chrono::steady_clock::now();
    run();
    const double measured = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return timing_ ? timing_(threads_, steps, measured) : measured;
  }

  static std::string threads_text(int32_t n) { return std::to_string(n) + " thread" + (n > 1 ? "s" : ""); }

  BackendTool tool_;
  SimdTarget simd_target_;  // the kernel's target
  int threads_;
  StepTiming timing_;                     // stands in for the clock in tests (thread choice)
  std::optional<ThreadChoice> choice_;    // set when the thread count is chosen by timing
  double live_share_ = 0;                 // CpuBackendOptions::live_share
  std::string device_;
  double time_ = 0;
  // The state lives in t_.kernel; these hold it across a rebuild and set_state.
  Soa3<Real> u_;  // displacements from rest at t (npoint)
  Soa3<Real> d_;  // step increments u_t - u_{t-1} (npoint)
  std::vector<int32_t> attached_;  // attachment index per point or -1 (npad)
  std::vector<int32_t> attached_points_;
  std::vector<Real> attach_offset_;  // pull: x_i - c at grasp time, 3 per attachment
  Tables t_;                         // the current version's
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend(const Model& model, const BackendTool& tool,
                                          const CpuBackendOptions& options, StepTiming timing) {
  if (options.precision == Precision::Float)
    return std::make_unique<CpuBackend<float>>(model, tool, options, std::move(timing));
  return std::make_unique<CpuBackend<double>>(model, tool, options, std::move(timing));
}

}  // namespace organsim
