#include "core/sim/cpu_backend.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>

#include "core/model/shear_element.h"
#include "core/physics/force_law.h"
#include "core/sim/cpu_kernel_avx512.h"
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

// Why the AVX-512 kernels cannot run this step plan here ("" if they can).
std::string avx512_refusal(const StepPlan& plan, const Model& model) {
  if (!avx512_kernel_compiled()) return "this build has no AVX-512 kernel (ORGANSIM_NATIVE=OFF or no AVX-512 CPU)";
  return avx512_kernel_unsupported(plan, model.layout.chunk_size);
}

// What the springs pass does with sutures, if the model has any.
std::string sutures_detail(const Model& m) {
  if (m.nsuture() == 0) return "";
  return ", " + std::to_string(m.nsuture()) + " of them sutures (tension only, rest length refreshed per tick)";
}

// Three coordinate arrays (structure of arrays), so that one slot of a
// group of lanes is a contiguous load and the compiler vectorises over lanes.
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
  void swap(Soa3& other) {
    x.swap(other.x);
    y.swap(other.y);
    z.swap(other.z);
  }
};

template <class Real>
class CpuBackend final : public Backend {
  // Lanes evaluated together: one 512-bit register of Real.
  static constexpr int32_t kLanes = 64 / static_cast<int32_t>(sizeof(Real));
  // The AVX-512 kernel of this precision.
  using FastKernel = Avx512Kernel<Real>;

 public:
  CpuBackend(const Model& model, const BackendTool& tool, const CpuBackendOptions& options, StepTiming timing)
      : model_(&model), tool_(tool), kernel_choice_(options.kernel),
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
    pack();
    std::string how;
    if (options.threads <= 0 && omp_get_max_threads() > 1) {
      how = choose_threads_by_timing();
      choice_.emplace(threads_, threads_ == 1 ? omp_get_max_threads() : 1);
    }
    device_ = cpu_model_name() + ", " + threads_text(threads_) + how;
  }

  void rebuild(const Model& next) override {
    const size_t old_n = u_.x.size(), n = static_cast<size_t>(next.npoint());
    if (n < old_n || next.origin.size() != n)
      throw Error(ErrorKind::Backend, "cpu backend: rebuild from a Model with " + std::to_string(n) +
                                          " points after " + std::to_string(old_n) + " (points are append-only)");
    model_ = &next;
    if (fast_) pull_fast_state();
    // An appended point copies its origin's displacement and increment: its
    // rest position is the origin's, so it starts at the same x_t and x_{t-1}.
    for (Soa3<Real>* s : {&u_, &d_}) {
      s->resize(n, 0);
      for (size_t i = old_n; i < n; ++i) s->copy(next.origin[i], i);
    }
    attached_.resize(n, -1);
    pack();
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
    return device_ + retimed + ", " + (fast_ ? "avx512" : "generic") + " kernel";
  }
  std::string precision() const override { return sizeof(Real) == 8 ? "double" : "float"; }
  int32_t reaction_latency_ticks() const override { return 0; }
  double time() const override { return time_; }

  const StepPlan& step_plan() const override { return plan_; }

  Plan plan() const override {
    Plan plan;
    for (Pass pass : plan_.passes) plan.passes.push_back({pass_name(pass), pass_detail(pass)});
    if (plan_.sutures > 0)
      plan.per_tick.push_back({"suture-rest", std::to_string(plan_.sutures) + " sutures' rest lengths from their schedule"});
    const auto& m = *model_;
    const size_t real = sizeof(Real), n = static_cast<size_t>(m.npoint());
    if (fast_) {
      plan.buffers.push_back({"avx512 kernel: point records, state, spring slots, tet batches, tet force slices",
                              fast_->bytes()});
    } else {
      plan.buffers.push_back({"X, u_t, d_t, u_{t+1}, d_{t+1}", 5 * n * 3 * real});
      plan.buffers.push_back({"mass, 1/mass", 2 * n * real});
      plan.buffers.push_back({"spring slots (other, rest, k, d)",
                              m.layout.springs.item.size() * (sizeof(int32_t) + 3 * real)});
      const size_t tet_slots = m.layout.tets.item.size();
      switch (plan_.element) {
        case ElementTerm::NodalVolume:
          plan.buffers.push_back({"tet slots (3 others)", tet_slots * 3 * sizeof(int32_t)});
          plan.buffers.push_back({"nodal k, rest volume, pressure", 3 * n * real});
          break;
        case ElementTerm::TetVolume:
          plan.buffers.push_back({"tet slots (3 others, rest volume, k_v)", tet_slots * (3 * sizeof(int32_t) + 2 * real)});
          break;
        case ElementTerm::SmoothedShear:
          plan.buffers.push_back({"smoothed shear: 1/K_a and the stress per point", 10 * n * real});
          [[fallthrough]];
        case ElementTerm::ShearElement:
          plan.buffers.push_back({"tet slots (3 others, 3 rest shape gradients, k_t)",
                                  tet_slots * (3 * sizeof(int32_t) + 10 * real)});
          break;
        case ElementTerm::None: break;
      }
    }
    if (plan_.tool != ToolTerm::None)
      plan.buffers.push_back({"tool partial sums per chunk", partial_.size() * sizeof(ChunkReaction)});
    plan.dispatches_per_step = 1;
    plan.syncs_per_step = 0;
    return plan;
  }

  // What this backend's kernel does for one pass of the step plan.
  std::string pass_detail(Pass pass) const {
    const auto& m = *model_;
    const std::string lanes = std::to_string(kLanes) + " " + precision() + " lanes";
    const std::string tets_per_vertex = std::to_string(m.ntet()) + " tets gathered per vertex (" +
                                        std::to_string(m.layout.tets.item.size()) + " slots)";
    const std::string tet_batches = std::to_string(m.ntet()) + " tets evaluated once, " + std::to_string(kLanes) +
                                    " per batch, ";
    switch (pass) {
      case Pass::NodalPressure:
        return fast_ ? tet_batches + "6 V_t into their vertices' nodal volumes (2 fixed slices), a barrier, "
                                     "the pressures per point, a barrier (avx512 kernel)"
                     : "nodal volumes and pressures, " + tets_per_vertex + ", then a barrier";
      case Pass::ShearSmoothing:
        return "every point's stress on its node-averaged deformation gradient, " +
               (fast_ ? "gathered over its spring slots, then a barrier (avx512 kernel)"
                      : tets_per_vertex + ", then a barrier");
      case Pass::Springs:
        return std::to_string(m.nspring()) + " springs gathered from both ends (" +
               std::to_string(m.layout.springs.item.size()) + " slots)" + sutures_detail(m);
      case Pass::Volume:
        return fast_ ? tet_batches + "into 2 fixed force slices (avx512 kernel)" : tets_per_vertex;
      case Pass::ShearElement:
        return std::string(plan_.element == ElementTerm::SmoothedShear ? "smoothed " : "") +
               "shear element (neo-Hookean, no lambda" + (m.shear_damping_time > 0 ? ", with its damper" : "") +
               "), " + (fast_ ? tet_batches + "into 2 fixed force slices (avx512 kernel)" : tets_per_vertex);
      case Pass::Gravity: return "m g on every free point";
      case Pass::SurfaceContact:
        return std::string(shape_name(tool_.shape)) + " against " + std::to_string(m.nsurface()) +
               " surface triangles, broad phase: the " + shape_name(tool_.shape) +
               " against each triangle's box; each touching "
               "triangle's penalty at its closest point, spread to its corners (box tests on the step's threads, "
               "penalties on one thread in triangle order)";
      case Pass::ToolContact:
        return plan_.tool == ToolTerm::Push      ? std::string(shape_name(tool_.shape)) + " penalty contact on the points"
               : plan_.tool == ToolTerm::Surface ? "the surface contact's forces on the touched points"
                                                 : "grasp attachment springs";
      case Pass::Integrate:
        return "position Verlet with drag, fused with the force passes (" + lanes +
               (fast_ ? ", avx512 kernel)" : ", generic kernel)");
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
    if (fast_) {
      const Real *ux = fast_->displacement(0), *uy = fast_->displacement(1), *uz = fast_->displacement(2);
      for (size_t i = 0; i < out.size(); ++i) out[i] = model_->rest_position[i] + Vec3(ux[i], uy[i], uz[i]);
      return;
    }
    for (size_t i = 0; i < out.size(); ++i) out[i] = model_->rest_position[i] + displacement(u_, i);
  }

  void set_state(const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev) override {
    if (x.size() != u_.x.size() || x_prev.size() != u_.x.size())
      throw Error(ErrorKind::Input, "set_state: expected " + std::to_string(u_.x.size()) + " positions");
    for (size_t i = 0; i < x.size(); ++i) {
      const Vec3 u = x[i] - model_->rest_position[i], d = x[i] - x_prev[i];
      u_.x[i] = static_cast<Real>(u.x());
      u_.y[i] = static_cast<Real>(u.y());
      u_.z[i] = static_cast<Real>(u.z());
      d_.x[i] = static_cast<Real>(d.x());
      d_.y[i] = static_cast<Real>(d.y());
      d_.z[i] = static_cast<Real>(d.z());
    }
    if (fast_) push_fast_state();
  }

  Reaction tick(const TickRequest& request) override {
    KernelStepInputs<Real> ctx;
    ctx.dt = static_cast<Real>(request.dt);
    ctx.inv_dt = static_cast<Real>(1.0 / request.dt);
    ctx.dt2 = static_cast<Real>(request.dt * request.dt);
    ctx.drag = static_cast<Real>(1.0 - model_->viscous_damping * request.dt);
    ctx.shear_damping = static_cast<Real>(model_->shear_damping_time / request.dt);
    for (int k = 0; k < 3; ++k) ctx.gravity[k] = static_cast<Real>(model_->gravity[k]);
    ctx.tool_radius = static_cast<Real>(tool_.radius);
    ctx.tool_k = static_cast<Real>(tool_.contact_stiffness);
    ctx.tool = request.tool_active ? plan_.tool : ToolTerm::None;
    ctx.attached = attached_.data();
    ctx.attach_offset = attach_offset_.data();
    ctx.tool_scale = tool_scale_.data();
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
      reaction = fast_ ? fast_step(ctx) : step(ctx);
      if (ctx.tool == ToolTerm::Surface) reaction.grip = static_cast<double>(surface_.grip());
      time_ += request.dt;
    };
    if (!choice_) {
      for (int32_t s = 0; s < request.substeps; ++s) substep(s);
      return reaction;
    }
    // Thread count chosen by timing: keep timing (thread_choice.h).
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
  // Calls f(entry, p) for every slot of `table`, padding included, with the
  // point p whose lane holds it (chunk by chunk, no search per entry).
  template <class F>
  void for_each_slot(const GatherTable& table, F f) const {
    const int32_t c = model_->layout.chunk_size;
    for (int32_t chunk = 0; chunk + 1 < static_cast<int32_t>(table.chunk_offset.size()); ++chunk)
      for (int32_t e = table.chunk_offset[chunk]; e < table.chunk_offset[chunk + 1]; ++e)
        f(e, chunk * c + (e - table.chunk_offset[chunk]) % c);
  }

  // Everything derived from the Model, in the backend's precision and slot
  // order; the constructor and rebuild() share it, so a topology change needs
  // no code of its own here.
  void pack() {
    const Model& model = *model_;
    plan_ = make_step_plan(model, tool_);
    const int32_t n = model.npoint();
    const auto& layout = model.layout;
    rest_.assign(n, 0);
    for (int32_t i = 0; i < n; ++i) {
      rest_.x[i] = static_cast<Real>(model.rest_position[i].x());
      rest_.y[i] = static_cast<Real>(model.rest_position[i].y());
      rest_.z[i] = static_cast<Real>(model.rest_position[i].z());
    }
    pos_ = rest_;
    u_next_.assign(n, 0);
    d_next_.assign(n, 0);

    // Per-slot copies of the parameters in the backend's precision, one
    // contiguous stream per slot. Padding slots point at their own point
    // with zero stiffness: a zero-length spring and a flat tet add nothing,
    // so the loops need no branch. Rest lengths and volumes are recomputed
    // from the rounded rest positions exactly as the loops compute them, so
    // the rest state is force-free in either precision.
    const auto& springs = layout.springs;
    spring_other_.resize(springs.item.size());
    spring_rest_.assign(springs.item.size(), 0);
    spring_k_.assign(springs.item.size(), 0);
    spring_d_.assign(springs.item.size(), 0);
    suture_slots_.clear();
    for_each_slot(springs, [&](int32_t e, int32_t p) {
      const int32_t s = springs.item[e];
      spring_other_[e] = s < 0 ? p : layout.spring_other[e];
      if (s < 0) return;
      spring_rest_[e] = rest_distance(p, spring_other_[e]);
      spring_k_[e] = static_cast<Real>(model.spring_k[s]);
      spring_d_[e] = static_cast<Real>(model.spring_d[s]);
      if (s >= model.first_suture()) {
        // A suture: tension only, marked by a negative stiffness in its slot
        // (no extra stream for the loop to read); its rest length follows
        // the schedule (refresh_suture_rest).
        spring_k_[e] = -spring_k_[e];
        suture_slots_.push_back({e, s});
      }
    });
    refresh_suture_rest();
    if (model.has_volume() || model.has_shear_element()) {
      const auto& tets = layout.tets;
      for (auto* v : {&tet_a_, &tet_b_, &tet_c_}) v->resize(tets.item.size());
      // The nodal term reads only the vertices of each slot.
      const size_t per_tet = model.has_nodal_volume() ? 0 : tets.item.size();
      tet_rest_.assign(per_tet, 0);
      tet_k_.assign(model.has_shear_element() ? tets.item.size() : per_tet, 0);
      // The shear element: rest gradients g_a, g_b, g_c of each slot's
      // others (padding: zero, no force).
      for (auto& g : shear_g_) g.assign(model.has_shear_element() ? tets.item.size() : 0, 0);
      for_each_slot(tets, [&](int32_t e, int32_t p) {
        const int32_t t = tets.item[e];
        const auto& o = layout.tet_others[e];
        tet_a_[e] = t < 0 ? p : o[0];
        tet_b_[e] = t < 0 ? p : o[1];
        tet_c_[e] = t < 0 ? p : o[2];
        if (t < 0 || model.has_nodal_volume()) return;
        if (model.has_shear_element()) {
          for (int k = 0; k < 3; ++k)
            for (int axis = 0; axis < 3; ++axis)
              shear_g_[3 * k + axis][e] = static_cast<Real>(shape_gradient_of(model, t, o[k])[axis]);
          tet_k_[e] = static_cast<Real>(model.tet_shear_k[t]);
          return;
        }
        tet_rest_[e] = rest_volume(p, o[0], o[1], o[2]);
        tet_k_[e] = static_cast<Real>(model.tet_k[t]);
      });
    }
    mass_.resize(n);
    inv_mass_.resize(n);
    tool_scale_.resize(n);
    for (int32_t i = 0; i < n; ++i) tool_scale_[i] = static_cast<Real>(model.tool_scale(i));
    for (int32_t i = 0; i < n; ++i) {
      mass_[i] = static_cast<Real>(model.mass[i]);
      inv_mass_[i] = static_cast<Real>(model.inv_mass[i]);
    }
    // Slots per group of lanes: the widest point of the group.
    const int32_t groups_per_chunk = (layout.chunk_size + kLanes - 1) / kLanes;
    spring_width_.assign(static_cast<size_t>(layout.nchunk) * groups_per_chunk, 0);
    tet_width_.assign(spring_width_.size(), 0);
    for (int32_t p = 0; p < n; ++p) {
      const int32_t c = p / layout.chunk_size, g = (p % layout.chunk_size) / kLanes;
      auto& sw = spring_width_[c * groups_per_chunk + g];
      auto& tw = tet_width_[c * groups_per_chunk + g];
      sw = std::max(sw, springs.count[p]);
      tw = std::max(tw, layout.tets.count[p]);
    }
    groups_per_chunk_ = groups_per_chunk;
    partial_.resize(layout.nchunk);
    if (model.has_nodal_volume()) {
      // Rest nodal volumes by the very pass the step runs (pos_ is at rest
      // here), so the rest state is exactly pressure-free in either precision.
      node_k_.resize(n);
      for (int32_t i = 0; i < n; ++i) node_k_[i] = static_cast<Real>(model.point_volume_k[i]);
      node_rest_.assign(n, 0);
      node_q_.assign(n, 0);
      for (int32_t c = 0; c < layout.nchunk; ++c) nodal_volume_chunk(c, node_rest_.data());
    } else {
      node_k_.clear(), node_rest_.clear(), node_q_.clear();
    }
    // The smoothed shear element: 1/K_p per point (0 in no tet: its stress
    // stays P(I) = 0) and the stresses, rewritten every step.
    node_inv_k_.clear();
    for (auto& a : node_stress_) a.assign(model.has_smoothed_shear() ? n : 0, 0);
    if (model.has_smoothed_shear()) {
      node_inv_k_.resize(n);
      for (int32_t i = 0; i < n; ++i)
        node_inv_k_[i] = model.point_shear_k[i] > 0 ? static_cast<Real>(1 / model.point_shear_k[i]) : Real(0);
    }
    smoothed_share_ = static_cast<Real>(model.shear_smoothed_share);
    pack_fast();
    if (plan_.tool == ToolTerm::Surface) surface_.pack(model, tool_scale_, tool_scale_.size());
  }

  // The surface-contact pass at this substep's positions (X + u): the
  // kernels' tool pass then adds its per-point forces.
  void surface_contact(KernelStepInputs<Real>& ctx, const ToolPlacement& placed) {
    const std::array<const Real*, 3> rest = {rest_.x.data(), rest_.y.data(), rest_.z.data()};
    const std::array<const Real*, 3> u =
        fast_ ? std::array<const Real*, 3>{fast_->displacement(0), fast_->displacement(1), fast_->displacement(2)}
              : std::array<const Real*, 3>{u_.x.data(), u_.y.data(), u_.z.data()};
    surface_.evaluate(rest, u, placed, ctx.tool_k, tool_.friction, threads_);
    ctx.contact_slot = surface_.slot();
    ctx.contact_force = surface_.force();
  }

  // Sutures tighten on their schedule: rest lengths at the start of the tick,
  // constant over its substeps. The few suture slots only; nothing allocates.
  void refresh_suture_rest() {
    for (const auto& [e, s] : suture_slots_) {
      spring_rest_[e] = static_cast<Real>(model_->spring_rest_at(s, time_));
      if (fast_) fast_->set_spring_rest(e, spring_rest_[e]);
    }
  }

  // The AVX-512 kernel packs its own streams from the same Model; while it
  // runs, it holds the state (u_, d_ are filled from it only for a rebuild).
  void pack_fast() {
    const std::string refusal = avx512_refusal(plan_, *model_);
    if (kernel_choice_ == CpuKernel::Avx512 && !refusal.empty())
      throw Error(ErrorKind::Backend, "cpu backend: the avx512 kernel cannot run this model: " + refusal);
    if (kernel_choice_ == CpuKernel::Generic || !refusal.empty()) {
      fast_.reset();
      return;
    }
    if (!fast_) fast_ = std::make_unique<FastKernel>();
    fast_->pack(*model_, plan_);
    refresh_suture_rest();
    fast_partial_.resize(fast_->nchunk());
    // The kernel reads attachment indices a register of points at a time, padding included.
    const size_t npad = static_cast<size_t>(fast_->nchunk()) * model_->layout.chunk_size;
    attached_.resize(std::max(attached_.size(), npad), -1);
    // Padding lanes (at the origin, no mass) may fall inside a push tool: scale 0.
    tool_scale_.resize(std::max(tool_scale_.size(), npad), 0);
    push_fast_state();
  }
  void push_fast_state() {
    for (size_t i = 0; i < u_.x.size(); ++i) {
      const Real u[3] = {u_.x[i], u_.y[i], u_.z[i]}, d[3] = {d_.x[i], d_.y[i], d_.z[i]};
      fast_->set_point(static_cast<int32_t>(i), u, d);
    }
  }
  void pull_fast_state() {
    Real u[3], d[3];
    for (size_t i = 0; i < u_.x.size(); ++i) {
      fast_->get_point(static_cast<int32_t>(i), u, d);
      u_.x[i] = u[0], u_.y[i] = u[1], u_.z[i] = u[2];
      d_.x[i] = d[0], d_.y[i] = d[1], d_.z[i] = d[2];
    }
  }

  Reaction fast_step(const KernelStepInputs<Real>& in) {
    fast_->step(in, threads_, fast_partial_);
    Reaction reaction;
    if (in.tool != ToolTerm::None) {
      // Fixed-order sum of per-chunk partials: identical for any thread count.
      for (const ChunkReaction& p : fast_partial_) {
        reaction.force += p.force;
        reaction.torque += p.torque;
        reaction.contacts += p.contacts;
      }
    }
    return reaction;
  }

  // Times steps from rest on 1 thread and on all hardware threads
  // (alternating, best of five each, at least ~2 ms of steps per timing so
  // that a liver-size model is timed over several steps, not one) and keeps
  // the faster; the state is put back to rest afterwards. Small models stay
  // on one thread when the fork/join costs more than it saves. Returns what
  // it measured, for device().
  std::string choose_threads_by_timing() {
    const int all = omp_get_max_threads();
    KernelStepInputs<Real> ctx{};
    ctx.dt = Real(1e-6), ctx.inv_dt = Real(1e6), ctx.dt2 = Real(1e-12), ctx.drag = Real(1);
    ctx.shear_damping = static_cast<Real>(model_->shear_damping_time * 1e6);
    auto time_steps = [&](int threads, int32_t steps) {
      threads_ = threads;
      return 1e3 * timed(steps, [&] {
               for (int32_t s = 0; s < steps; ++s) fast_ ? fast_step(ctx) : step(ctx);
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
    if (fast_) push_fast_state();
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

  static Vec3 displacement(const Soa3<Real>& u, size_t i) {
    return Vec3(static_cast<double>(u.x[i]), static_cast<double>(u.y[i]), static_cast<double>(u.z[i]));
  }
  Real rest_distance(int32_t p, int32_t q) const {
    const Real dx = rest_.x[q] - rest_.x[p], dy = rest_.y[q] - rest_.y[p], dz = rest_.z[q] - rest_.z[p];
    return std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  Real rest_volume(int32_t p, int32_t a, int32_t b, int32_t c) const {
    auto d = [&](int32_t q, const std::vector<Real>& v) { return v[q] - v[p]; };
    const Real ax = d(a, rest_.x), ay = d(a, rest_.y), az = d(a, rest_.z);
    const Real bx = d(b, rest_.x), by = d(b, rest_.y), bz = d(b, rest_.z);
    const Real cx = d(c, rest_.x), cy = d(c, rest_.y), cz = d(c, rest_.z);
    return (ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)) / Real(6);
  }

  // Each combination of the plan's passes is its own compiled loop, so a
  // lean scene never touches the code or data of a pass it lacks.
  Reaction step(const KernelStepInputs<Real>& ctx) {
    switch (plan_.element) {
      case ElementTerm::NodalVolume: return dispatch_gravity<ElementTerm::NodalVolume>(ctx);
      case ElementTerm::TetVolume: return dispatch_gravity<ElementTerm::TetVolume>(ctx);
      case ElementTerm::SmoothedShear: return dispatch_gravity<ElementTerm::SmoothedShear>(ctx);
      case ElementTerm::ShearElement: return dispatch_gravity<ElementTerm::ShearElement>(ctx);
      case ElementTerm::None: break;
    }
    return dispatch_gravity<ElementTerm::None>(ctx);
  }

  template <ElementTerm Volume>
  Reaction dispatch_gravity(const KernelStepInputs<Real>& ctx) {
    return plan_.gravity ? dispatch_tool<Volume, true>(ctx) : dispatch_tool<Volume, false>(ctx);
  }

  template <ElementTerm Volume, bool Gravity>
  Reaction dispatch_tool(const KernelStepInputs<Real>& ctx) {
    switch (ctx.tool) {
      case ToolTerm::Push: return run<Volume, Gravity, ToolTerm::Push>(ctx);
      case ToolTerm::Pull: return run<Volume, Gravity, ToolTerm::Pull>(ctx);
      case ToolTerm::Surface: return run<Volume, Gravity, ToolTerm::Surface>(ctx);
      case ToolTerm::None: break;
    }
    return run<Volume, Gravity, ToolTerm::None>(ctx);
  }

  template <ElementTerm Volume, bool Gravity, ToolTerm Tool>
  Reaction run(const KernelStepInputs<Real>& ctx) {
    const int32_t nchunk = model_->layout.nchunk, npoint = model_->npoint();
#pragma omp parallel num_threads(threads_)
    {
      // Positions x = X + u once per step: the gathers below then fetch 3
      // coordinates per neighbour instead of 6. Integration stays on u and d.
#pragma omp for simd schedule(static)
      for (int32_t p = 0; p < npoint; ++p) {
        pos_.x[p] = rest_.x[p] + u_.x[p];
        pos_.y[p] = rest_.y[p] + u_.y[p];
        pos_.z[p] = rest_.z[p] + u_.z[p];
      }
      if constexpr (Volume == ElementTerm::NodalVolume) {
        // The nodal term's extra pass: every point's pressure before any force.
#pragma omp for schedule(static)
        for (int32_t c = 0; c < nchunk; ++c) nodal_pressure_chunk(c);
      }
      if constexpr (Volume == ElementTerm::SmoothedShear) {
        // Every point's smoothed stress before any force reads it.
#pragma omp for schedule(static)
        for (int32_t c = 0; c < nchunk; ++c) shear_stress_chunk(c);
      }
#pragma omp for schedule(static)
      for (int32_t c = 0; c < nchunk; ++c) chunk<Volume, Gravity, Tool>(ctx, c);
    }
    u_.swap(u_next_);  // u_t <- u_{t+1}
    d_.swap(d_next_);  // d_t <- d_{t+1}
    Reaction reaction;
    if constexpr (Tool != ToolTerm::None) {
      // Fixed-order sum of per-chunk partials: identical for any thread count.
      for (const ChunkReaction& p : partial_) {
        reaction.force += p.force;
        reaction.torque += p.torque;
        reaction.contacts += p.contacts;
      }
    }
    return reaction;
  }

  // Nodal volumes V_p = sum over the tets of p of V_t / 4 at pos_, for the
  // points of chunk c, into out. Not inlined: pack() and the step must run
  // the same instructions so the rest state gives exactly V_p^r.
  __attribute__((noinline)) void nodal_volume_chunk(int32_t c, Real* __restrict out) const {
    const auto& L = model_->layout;
    const int32_t C = L.chunk_size;
    const int32_t first = c * C, last = std::min(model_->npoint(), first + C);
    const Real* __restrict X = pos_.x.data();
    const Real* __restrict Y = pos_.y.data();
    const Real* __restrict Z = pos_.z.data();
    const int32_t* __restrict ta = tet_a_.data();
    const int32_t* __restrict tb = tet_b_.data();
    const int32_t* __restrict tc = tet_c_.data();
    for (int32_t g0 = first; g0 < last; g0 += kLanes) {
      const int32_t lanes = std::min(kLanes, last - g0);
      const int32_t lane0 = g0 - first;
      const int32_t group = c * groups_per_chunk_ + lane0 / kLanes;
      alignas(64) Real v[kLanes] = {};
      for (int32_t j = 0; j < tet_width_[group]; ++j) {
        const int32_t e0 = L.tets.chunk_offset[c] + j * C + lane0;
#pragma omp simd
        for (int32_t l = 0; l < lanes; ++l) {
          const int32_t e = e0 + l, p = g0 + l, a = ta[e], b = tb[e], cc = tc[e];
          const Real ax = X[a] - X[p], ay = Y[a] - Y[p], az = Z[a] - Z[p];
          const Real bx = X[b] - X[p], by = Y[b] - Y[p], bz = Z[b] - Z[p];
          const Real cx = X[cc] - X[p], cy = Y[cc] - Y[p], cz = Z[cc] - Z[p];
          v[l] += (ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)) / Real(24);
        }
      }
      for (int32_t l = 0; l < lanes; ++l) out[g0 + l] = v[l];
    }
  }

  // Nodal pressures q_p = k_p (V_p - V_p^r) of chunk c into node_q_.
  void nodal_pressure_chunk(int32_t c) {
    nodal_volume_chunk(c, node_q_.data());
    const int32_t first = c * model_->layout.chunk_size;
    const int32_t last = std::min(model_->npoint(), first + model_->layout.chunk_size);
#pragma omp simd
    for (int32_t p = first; p < last; ++p) node_q_[p] = force_law::volume_pressure(node_k_[p], node_q_[p], node_rest_[p]);
  }

  // The smoothed shear element's stress P(Fbar_p) = Fbar + phi'(J) cof Fbar
  // of the points of chunk c into node_stress_ (row-major), with
  // Fbar_p - I = sum over p's tet slots of k_t H_t / K_p and H_t = sum over
  // the others q of (u_q - u_p) g_q^T, from displacements as in the force
  // pass: at rest H = 0 exactly, Fbar = I and P = 0 in either precision.
  void shear_stress_chunk(int32_t c) {
    const auto& L = model_->layout;
    const int32_t C = L.chunk_size;
    const int32_t first = c * C, last = std::min(model_->npoint(), first + C);
    const Real* __restrict ux = u_.x.data();
    const Real* __restrict uy = u_.y.data();
    const Real* __restrict uz = u_.z.data();
    const int32_t* __restrict ta = tet_a_.data();
    const int32_t* __restrict tb = tet_b_.data();
    const int32_t* __restrict tc = tet_c_.data();
    const Real* __restrict kt = tet_k_.data();
    const std::array<const Real*, 9> g = {shear_g_[0].data(), shear_g_[1].data(), shear_g_[2].data(),
                                          shear_g_[3].data(), shear_g_[4].data(), shear_g_[5].data(),
                                          shear_g_[6].data(), shear_g_[7].data(), shear_g_[8].data()};
    for (int32_t g0 = first; g0 < last; g0 += kLanes) {
      const int32_t lanes = std::min(kLanes, last - g0);
      const int32_t lane0 = g0 - first;
      const int32_t group = c * groups_per_chunk_ + lane0 / kLanes;
      alignas(64) Real h[9][kLanes] = {};
      for (int32_t j = 0; j < tet_width_[group]; ++j) {
        const int32_t e0 = L.tets.chunk_offset[c] + j * C + lane0;
#pragma omp simd
        for (int32_t l = 0; l < lanes; ++l) {
          const int32_t e = e0 + l, p = g0 + l, a = ta[e], b = tb[e], cc = tc[e];
          const Real d[3][3] = {{ux[a] - ux[p], uy[a] - uy[p], uz[a] - uz[p]},
                                {ux[b] - ux[p], uy[b] - uy[p], uz[b] - uz[p]},
                                {ux[cc] - ux[p], uy[cc] - uy[p], uz[cc] - uz[p]}};
          for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k)
              h[3 * r + k][l] += kt[e] * (d[0][r] * g[k][e] + d[1][r] * g[3 + k][e] + d[2][r] * g[6 + k][e]);
        }
      }
#pragma omp simd
      for (int32_t l = 0; l < lanes; ++l) {
        const int32_t p = g0 + l;
        const Real w = node_inv_k_[p];
        const Real f00 = 1 + w * h[0][l], f01 = w * h[1][l], f02 = w * h[2][l];
        const Real f10 = w * h[3][l], f11 = 1 + w * h[4][l], f12 = w * h[5][l];
        const Real f20 = w * h[6][l], f21 = w * h[7][l], f22 = 1 + w * h[8][l];
        const Real k00 = f11 * f22 - f12 * f21, k01 = f12 * f20 - f10 * f22, k02 = f10 * f21 - f11 * f20;
        const Real k10 = f02 * f21 - f01 * f22, k11 = f00 * f22 - f02 * f20, k12 = f01 * f20 - f00 * f21;
        const Real k20 = f01 * f12 - f02 * f11, k21 = f02 * f10 - f00 * f12, k22 = f00 * f11 - f01 * f10;
        const Real slope = force_law::shear_barrier_slope(f00 * k00 + f01 * k01 + f02 * k02);
        node_stress_[0][p] = f00 + slope * k00;
        node_stress_[1][p] = f01 + slope * k01;
        node_stress_[2][p] = f02 + slope * k02;
        node_stress_[3][p] = f10 + slope * k10;
        node_stress_[4][p] = f11 + slope * k11;
        node_stress_[5][p] = f12 + slope * k12;
        node_stress_[6][p] = f20 + slope * k20;
        node_stress_[7][p] = f21 + slope * k21;
        node_stress_[8][p] = f22 + slope * k22;
      }
    }
  }

  template <ElementTerm Volume, bool Gravity, ToolTerm Tool>
  void chunk(const KernelStepInputs<Real>& ctx, int32_t c) {
    const auto& L = model_->layout;
    const int32_t C = L.chunk_size;
    const int32_t first = c * C, last = std::min(model_->npoint(), first + C);
    ChunkReaction partial;
    const Real* __restrict X = pos_.x.data();
    const Real* __restrict Y = pos_.y.data();
    const Real* __restrict Z = pos_.z.data();
    const Real* __restrict ux = u_.x.data();
    const Real* __restrict uy = u_.y.data();
    const Real* __restrict uz = u_.z.data();
    const Real* __restrict dx = d_.x.data();
    const Real* __restrict dy = d_.y.data();
    const Real* __restrict dz = d_.z.data();
    for (int32_t g0 = first; g0 < last; g0 += kLanes) {
      const int32_t lanes = std::min(kLanes, last - g0);
      const int32_t lane0 = g0 - first;
      const int32_t group = c * groups_per_chunk_ + lane0 / kLanes;
      alignas(64) Real fx[kLanes], fy[kLanes], fz[kLanes];
#pragma omp simd
      for (int32_t l = 0; l < lanes; ++l) {
        const int32_t p = g0 + l;
        fx[l] = Gravity ? mass_[p] * ctx.gravity[0] : Real(0);
        fy[l] = Gravity ? mass_[p] * ctx.gravity[1] : Real(0);
        fz[l] = Gravity ? mass_[p] * ctx.gravity[2] : Real(0);
      }

      // Springs + dampers: f = [k (L - r) + d (dv . l/L)] l/L, l = x_q - x_p.
      // A suture (k < 0 in its slot, stiffness |k|) pulls only: no force while
      // slack (L <= r), and a closing damper never turns the pull into a push.
      const int32_t* __restrict other = spring_other_.data();
      const Real* __restrict rest = spring_rest_.data();
      const Real* __restrict k = spring_k_.data();
      const Real* __restrict d = spring_d_.data();
      for (int32_t j = 0; j < spring_width_[group]; ++j) {
        const int32_t e0 = L.springs.chunk_offset[c] + j * C + lane0;
#pragma omp simd
        for (int32_t l = 0; l < lanes; ++l) {
          const int32_t e = e0 + l, p = g0 + l, q = other[e];
          const Real lx = X[q] - X[p], ly = Y[q] - Y[p], lz = Z[q] - Z[p];
          const Real length = std::sqrt(lx * lx + ly * ly + lz * lz);
          // Coincident ends (and padding slots) have no direction: no force.
          const Real inv = length > Real(0) ? Real(1) / length : Real(0);
          const Real dvx = dx[q] - dx[p], dvy = dy[q] - dy[p], dvz = dz[q] - dz[p];
          const Real along = (dvx * lx + dvy * ly + dvz * lz) * inv * ctx.inv_dt;  // closing rate, m/s
          const Real ke = k[e];
          const Real tension = force_law::spring_tension(std::abs(ke), d[e], length, rest[e], along);
          const Real s = (ke < Real(0) ? force_law::suture_tension(tension, length, rest[e]) : tension) * inv;
          fx[l] += s * lx;
          fy[l] += s * ly;
          fz[l] += s * lz;
        }
      }

      if constexpr (Volume == ElementTerm::ShearElement || Volume == ElementTerm::SmoothedShear) {
        // f_p = -k (F + phi'(J) cof F) g_p = k (F s + phi'(J) cof(F) s) with
        // F = I + H, H = sum over the others q of (u_q - u_p) g_q^T and
        // s = g_a + g_b + g_c = -g_p (core/model/shear_element.h). From
        // displacements: F = I, cof F = I, J = 1 exactly at rest, no force.
        // Its damper: f_p += (tau k / (dt J_d)) (G (cof^T c) + cof (G^T c)),
        // c = cof s, G = sum over the others q of (d_q - d_p) g_q^T = dt Fdot,
        // J_d = max(J, J_min): -(2 tau k / J_d) sym(Fdot cof^T) cof g_p.
        const int32_t* __restrict ta = tet_a_.data();
        const int32_t* __restrict tb = tet_b_.data();
        const int32_t* __restrict tc = tet_c_.data();
        const Real* __restrict kt = tet_k_.data();
        const Real* __restrict gax = shear_g_[0].data();
        const Real* __restrict gay = shear_g_[1].data();
        const Real* __restrict gaz = shear_g_[2].data();
        const Real* __restrict gbx = shear_g_[3].data();
        const Real* __restrict gby = shear_g_[4].data();
        const Real* __restrict gbz = shear_g_[5].data();
        const Real* __restrict gcx = shear_g_[6].data();
        const Real* __restrict gcy = shear_g_[7].data();
        const Real* __restrict gcz = shear_g_[8].data();
        // Smoothed: the per-tet stress weighs 1 - s, the mean of the four
        // corners' smoothed stresses s (their sum times s / 4).
        constexpr bool smoothed = Volume == ElementTerm::SmoothedShear;
        const Real per_tet = smoothed ? 1 - smoothed_share_ : Real(1), corners = smoothed ? smoothed_share_ / 4 : Real(0);
        const std::array<const Real*, 9> P = {node_stress_[0].data(), node_stress_[1].data(), node_stress_[2].data(),
                                              node_stress_[3].data(), node_stress_[4].data(), node_stress_[5].data(),
                                              node_stress_[6].data(), node_stress_[7].data(), node_stress_[8].data()};
        for (int32_t j = 0; j < tet_width_[group]; ++j) {
          const int32_t e0 = L.tets.chunk_offset[c] + j * C + lane0;
#pragma omp simd
          for (int32_t l = 0; l < lanes; ++l) {
            const int32_t e = e0 + l, p = g0 + l, a = ta[e], b = tb[e], cc = tc[e];
            const Real ax = ux[a] - ux[p], ay = uy[a] - uy[p], az = uz[a] - uz[p];
            const Real bx = ux[b] - ux[p], by = uy[b] - uy[p], bz = uz[b] - uz[p];
            const Real cx = ux[cc] - ux[p], cy = uy[cc] - uy[p], cz = uz[cc] - uz[p];
            const Real f00 = 1 + ax * gax[e] + bx * gbx[e] + cx * gcx[e];
            const Real f01 = ax * gay[e] + bx * gby[e] + cx * gcy[e];
            const Real f02 = ax * gaz[e] + bx * gbz[e] + cx * gcz[e];
            const Real f10 = ay * gax[e] + by * gbx[e] + cy * gcx[e];
            const Real f11 = 1 + ay * gay[e] + by * gby[e] + cy * gcy[e];
            const Real f12 = ay * gaz[e] + by * gbz[e] + cy * gcz[e];
            const Real f20 = az * gax[e] + bz * gbx[e] + cz * gcx[e];
            const Real f21 = az * gay[e] + bz * gby[e] + cz * gcy[e];
            const Real f22 = 1 + az * gaz[e] + bz * gbz[e] + cz * gcz[e];
            // Cofactors: cof_ij = (-1)^(i+j) times the minor of F_ij.
            const Real k00 = f11 * f22 - f12 * f21, k01 = f12 * f20 - f10 * f22, k02 = f10 * f21 - f11 * f20;
            const Real k10 = f02 * f21 - f01 * f22, k11 = f00 * f22 - f02 * f20, k12 = f01 * f20 - f00 * f21;
            const Real k20 = f01 * f12 - f02 * f11, k21 = f02 * f10 - f00 * f12, k22 = f00 * f11 - f01 * f10;
            const Real J = f00 * k00 + f01 * k01 + f02 * k02;
            const Real slope = force_law::shear_barrier_slope(J);
            const Real sx = gax[e] + gbx[e] + gcx[e], sy = gay[e] + gby[e] + gcy[e], sz = gaz[e] + gbz[e] + gcz[e];
            const Real cx0 = k00 * sx + k01 * sy + k02 * sz;  // c = cof s
            const Real cx1 = k10 * sx + k11 * sy + k12 * sz;
            const Real cx2 = k20 * sx + k21 * sy + k22 * sz;
            const Real da_x = dx[a] - dx[p], da_y = dy[a] - dy[p], da_z = dz[a] - dz[p];
            const Real db_x = dx[b] - dx[p], db_y = dy[b] - dy[p], db_z = dz[b] - dz[p];
            const Real dc_x = dx[cc] - dx[p], dc_y = dy[cc] - dy[p], dc_z = dz[cc] - dz[p];
            const Real g00 = da_x * gax[e] + db_x * gbx[e] + dc_x * gcx[e];
            const Real g01 = da_x * gay[e] + db_x * gby[e] + dc_x * gcy[e];
            const Real g02 = da_x * gaz[e] + db_x * gbz[e] + dc_x * gcz[e];
            const Real g10 = da_y * gax[e] + db_y * gbx[e] + dc_y * gcx[e];
            const Real g11 = da_y * gay[e] + db_y * gby[e] + dc_y * gcy[e];
            const Real g12 = da_y * gaz[e] + db_y * gbz[e] + dc_y * gcz[e];
            const Real g20 = da_z * gax[e] + db_z * gbx[e] + dc_z * gcx[e];
            const Real g21 = da_z * gay[e] + db_z * gby[e] + dc_z * gcy[e];
            const Real g22 = da_z * gaz[e] + db_z * gbz[e] + dc_z * gcz[e];
            const Real w0 = k00 * cx0 + k10 * cx1 + k20 * cx2;  // cof^T c
            const Real w1 = k01 * cx0 + k11 * cx1 + k21 * cx2;
            const Real w2 = k02 * cx0 + k12 * cx1 + k22 * cx2;
            const Real h0 = g00 * cx0 + g10 * cx1 + g20 * cx2;  // G^T c
            const Real h1 = g01 * cx0 + g11 * cx1 + g21 * cx2;
            const Real h2 = g02 * cx0 + g12 * cx1 + g22 * cx2;
            const Real jm = static_cast<Real>(force_law::kShearElementMinJ);
            const Real damper = ctx.shear_damping / (J > jm ? J : jm);
            Real ex = per_tet * (f00 * sx + f01 * sy + f02 * sz + slope * cx0);
            Real ey = per_tet * (f10 * sx + f11 * sy + f12 * sz + slope * cx1);
            Real ez = per_tet * (f20 * sx + f21 * sy + f22 * sz + slope * cx2);
            if constexpr (smoothed) {
              // The corners' summed smoothed stresses applied to s.
              auto sum = [&](int i) { return P[i][p] + P[i][a] + P[i][b] + P[i][cc]; };
              ex += corners * (sum(0) * sx + sum(1) * sy + sum(2) * sz);
              ey += corners * (sum(3) * sx + sum(4) * sy + sum(5) * sz);
              ez += corners * (sum(6) * sx + sum(7) * sy + sum(8) * sz);
            }
            fx[l] += kt[e] * (ex + damper * (g00 * w0 + g01 * w1 + g02 * w2 + k00 * h0 + k01 * h1 + k02 * h2));
            fy[l] += kt[e] * (ey + damper * (g10 * w0 + g11 * w1 + g12 * w2 + k10 * h0 + k11 * h1 + k12 * h2));
            fz[l] += kt[e] * (ez + damper * (g20 * w0 + g21 * w1 + g22 * w2 + k20 * h0 + k21 * h1 + k22 * h2));
          }
        }
      } else if constexpr (Volume != ElementTerm::None) {
        // f_p = -p dV/dx_p, dV/dx_p = (c - a) x (b - a) / 6, with the tet's
        // pressure p = k_v (V - V_r), or the mean of its 4 nodal pressures.
        const Real* __restrict q = node_q_.data();
        const int32_t* __restrict ta = tet_a_.data();
        const int32_t* __restrict tb = tet_b_.data();
        const int32_t* __restrict tc = tet_c_.data();
        const Real* __restrict vr = tet_rest_.data();
        const Real* __restrict kv = tet_k_.data();
        for (int32_t j = 0; j < tet_width_[group]; ++j) {
          const int32_t e0 = L.tets.chunk_offset[c] + j * C + lane0;
#pragma omp simd
          for (int32_t l = 0; l < lanes; ++l) {
            const int32_t e = e0 + l, p = g0 + l, a = ta[e], b = tb[e], cc = tc[e];
            const Real ax = X[a] - X[p], ay = Y[a] - Y[p], az = Z[a] - Z[p];
            const Real bx = X[b] - X[p], by = Y[b] - Y[p], bz = Z[b] - Z[p];
            const Real cx = X[cc] - X[p], cy = Y[cc] - Y[p], cz = Z[cc] - Z[p];
            Real pressure;
            if constexpr (Volume == ElementTerm::NodalVolume) {
              pressure = force_law::tet_pressure_from_nodal(q[p], q[a], q[b], q[cc]);
            } else {
              const Real volume =
                  (ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)) / Real(6);
              pressure = force_law::volume_pressure(kv[e], volume, vr[e]);
            }
            const Real s = -pressure / Real(6);
            const Real ex = cx - ax, ey = cy - ay, ez = cz - az;  // c - a
            const Real gx = bx - ax, gy = by - ay, gz = bz - az;  // b - a
            fx[l] += s * (ey * gz - ez * gy);
            fy[l] += s * (ez * gx - ex * gz);
            fz[l] += s * (ex * gy - ey * gx);
          }
        }
      }

      if constexpr (Tool != ToolTerm::None) {
        // Few points touch the tool: a plain loop, reaction summed per lane in order.
        for (int32_t l = 0; l < lanes; ++l) {
          const Real xl[3] = {X[g0 + l], Y[g0 + l], Z[g0 + l]};
          Real fl[3] = {fx[l], fy[l], fz[l]};
          if (!add_tool_force<Real, Tool>(ctx, g0 + l, xl, fl, partial)) continue;
          fx[l] = fl[0], fy[l] = fl[1], fz[l] = fl[2];
        }
      }

      // Position Verlet with drag: d' = (1 - alpha dt) d + dt^2 F/m,
      // u' = u + d'. Fixed points (1/m = 0) stay put.
      Real* __restrict nx = u_next_.x.data();
      Real* __restrict ny = u_next_.y.data();
      Real* __restrict nz = u_next_.z.data();
      Real* __restrict ndx = d_next_.x.data();
      Real* __restrict ndy = d_next_.y.data();
      Real* __restrict ndz = d_next_.z.data();
#pragma omp simd
      for (int32_t l = 0; l < lanes; ++l) {
        const int32_t p = g0 + l;
        const Real w = inv_mass_[p] * ctx.dt2;
        const bool free = inv_mass_[p] > Real(0);
        ndx[p] = free ? ctx.drag * dx[p] + w * fx[l] : Real(0);
        ndy[p] = free ? ctx.drag * dy[p] + w * fy[l] : Real(0);
        ndz[p] = free ? ctx.drag * dz[p] + w * fz[l] : Real(0);
        nx[p] = ux[p] + ndx[p];
        ny[p] = uy[p] + ndy[p];
        nz[p] = uz[p] + ndz[p];
      }
    }
    if constexpr (Tool != ToolTerm::None) partial_[c] = partial;
  }

  const Model* model_;  // the current version (rebuild() moves it on)
  StepPlan plan_;       // the passes of its step (pack() computes it for each version)
  BackendTool tool_;
  CpuKernel kernel_choice_;
  int threads_;
  StepTiming timing_;                     // stands in for the clock in tests (thread choice)
  std::optional<ThreadChoice> choice_;    // set when the thread count is chosen by timing
  std::unique_ptr<FastKernel> fast_;         // set when the AVX-512 kernel runs this backend
  std::vector<ChunkReaction> fast_partial_;  // its tool reaction per chunk
  std::string device_;
  double time_ = 0;
  Soa3<Real> rest_;                   // X, rest positions (npoint)
  Soa3<Real> pos_;                    // x = X + u of the current step (npoint)
  Soa3<Real> u_, u_next_;             // displacements from rest at t, t+1 (npoint)
  Soa3<Real> d_, d_next_;             // step increments u_t - u_{t-1}, u_{t+1} - u_t (npoint)
  std::vector<int32_t> spring_other_;  // per slot, self for padding (nentry)
  std::vector<Real> spring_rest_, spring_k_, spring_d_;  // per slot (nentry); k < 0 marks a suture
  std::vector<std::pair<int32_t, int32_t>> suture_slots_;  // (slot, spring) of every suture slot
  std::vector<int32_t> tet_a_, tet_b_, tet_c_;  // per slot, self for padding (nentry); empty without volume
  std::vector<Real> tet_rest_, tet_k_;          // per slot (nentry); zero with the nodal term; k_t with the shear element
  std::array<std::vector<Real>, 9> shear_g_;    // shear element: g_a, g_b, g_c (x, y, z each) per slot (nentry); else empty
  std::vector<Real> node_k_, node_rest_, node_q_;  // nodal term: k_a, V_a^r, pressure (npoint); else empty
  std::vector<Real> node_inv_k_;                     // smoothed shear element: 1/K_a (npoint); else empty
  std::array<std::vector<Real>, 9> node_stress_;     // its P(Fbar_a), row-major (npoint each); else empty
  Real smoothed_share_ = 0;                          // its s (Model::shear_smoothed_share)
  std::vector<int32_t> spring_width_, tet_width_;  // slots per lane group (nchunk x groups)
  int32_t groups_per_chunk_ = 1;
  std::vector<Real> mass_, inv_mass_;
  std::vector<Real> tool_scale_;   // tool stiffness multiplier per point, Model::tool_k_scale (npoint; npad for the AVX-512 kernel, 0 for padding)
  std::vector<int32_t> attached_;  // attachment index per point or -1 (npoint)
  std::vector<int32_t> attached_points_;
  std::vector<Real> attach_offset_;  // pull: x_i - c at grasp time, 3 per attachment
  std::vector<ChunkReaction> partial_;   // tool reaction per chunk (nchunk)
  SurfaceContact<Real> surface_;         // the surface-contact pass (a pushing tool on the surface)
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend(const Model& model, const BackendTool& tool,
                                          const CpuBackendOptions& options, StepTiming timing) {
  if (options.precision == Precision::Float)
    return std::make_unique<CpuBackend<float>>(model, tool, options, std::move(timing));
  return std::make_unique<CpuBackend<double>>(model, tool, options, std::move(timing));
}

}  // namespace organsim
