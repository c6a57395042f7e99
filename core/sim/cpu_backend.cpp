#include "core/sim/cpu_backend.h"
#include "core/sim/contact_plan.h"

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

// Everything a CpuBackend derives from one Model version, in its precision
// and slot order, with the scratch sized by it: packed off the tick's path
// by prepare() and swapped in by adopt() with one move.
template <class Real>
struct CpuTables {
  const Model* model = nullptr;  // the version they were packed from
  StepPlan plan;                 // the passes of its step
  std::unique_ptr<SimdKernel<Real>> fast;  // set when the simd kernel runs this version
  std::vector<ChunkReaction> fast_partial;   // its tool reaction per chunk
  Soa3<Real> rest;                   // X, rest positions (npoint)
  Soa3<Real> pos;                    // x = X + u of the current step (npoint)
  Soa3<Real> u_next, d_next;         // u_{t+1}, d_{t+1} (npoint)
  std::vector<int32_t> spring_other;  // per slot, self for padding (nentry)
  std::vector<Real> spring_rest, spring_k, spring_d;  // per slot (nentry); k < 0 marks a suture
  std::vector<std::pair<int32_t, int32_t>> suture_slots;  // (slot, spring) of every suture slot
  std::vector<int32_t> tet_a, tet_b, tet_c;  // per slot, self for padding (nentry); empty without volume
  std::vector<Real> tet_rest, tet_k;          // per slot (nentry); zero with the nodal term; k_t with the shear element
  std::array<std::vector<Real>, 9> shear_g;    // shear element: g_a, g_b, g_c (x, y, z each) per slot (nentry); else empty
  std::vector<Real> node_k, node_rest, node_q;  // nodal term: k_a, V_a^r, pressure (npoint); else empty
  std::vector<Real> node_inv_k;                     // smoothed shear element: 1/K_a (npoint); else empty
  std::array<std::vector<Real>, 9> node_stress;     // its P(Fbar_a), row-major (npoint each); else empty
  Real smoothed_share = 0;                          // its s (Model::shear_smoothed_share)
  std::vector<int32_t> spring_width, tet_width;  // slots per lane group (nchunk x groups)
  int32_t groups_per_chunk = 1;
  std::vector<Real> mass, inv_mass;
  std::vector<Real> tool_scale;   // tool stiffness multiplier per point, Model::tool_k_scale (npoint; npad for the simd kernel, 0 for padding)
  std::vector<ChunkReaction> partial;   // tool reaction per chunk (nchunk)
  SurfaceContact<Real> surface;         // the surface-contact pass (a pushing tool on the surface)
};

// What CpuBackend::prepare hands to adopt.
template <class Real>
struct CpuPrepared final : PreparedModel {
  explicit CpuPrepared(const Model& next) : PreparedModel(next) {}
  CpuTables<Real> tables;
};

template <class Real>
class CpuBackend final : public Backend {
  // The generic kernel's lanes evaluated together: 64 bytes of Real (the
  // simd kernel has its own target's register width, SimdKernel::lanes()).
  static constexpr int32_t kLanes = 64 / static_cast<int32_t>(sizeof(Real));
  using Tables = CpuTables<Real>;

 public:
  CpuBackend(const Model& model, const BackendTool& tool, const CpuBackendOptions& options, StepTiming timing)
      : tool_(tool), kernel_choice_(options.kernel),
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
    if (t_.fast) pull_fast_state();
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
  // "simd (avx2)", ..., or "generic".
  std::string kernel_name() const { return t_.fast ? "simd (" + t_.fast->target().name + ")" : "generic"; }
  int32_t reaction_latency_ticks() const override { return 0; }
  double time() const override { return time_; }

  const StepPlan& step_plan() const override { return t_.plan; }

  Plan plan() const override {
    Plan plan;
    for (Pass pass : t_.plan.passes) plan.passes.push_back({pass_name(pass), pass_detail(pass)});
    if (t_.plan.sutures > 0)
      plan.per_tick.push_back({"suture-rest", std::to_string(t_.plan.sutures) + " sutures' rest lengths from their schedule"});
    const auto& m = *t_.model;
    const size_t real = sizeof(Real), n = static_cast<size_t>(m.npoint());
    if (t_.fast) {
      plan.buffers.push_back({kernel_name() + " kernel: point records, state, spring slots, tet batches, tet force slices",
                              t_.fast->bytes()});
    } else {
      plan.buffers.push_back({"X, u_t, d_t, u_{t+1}, d_{t+1}", 5 * n * 3 * real});
      plan.buffers.push_back({"mass, 1/mass", 2 * n * real});
      plan.buffers.push_back({"spring slots (other, rest, k, d)",
                              m.layout.springs.item.size() * (sizeof(int32_t) + 3 * real)});
      const size_t tet_slots = m.layout.tets.item.size();
      switch (t_.plan.element) {
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
    if (t_.plan.tool != ToolTerm::None)
      plan.buffers.push_back({"tool partial sums per chunk", t_.partial.size() * sizeof(ChunkReaction)});
    plan.dispatches_per_step = 1;
    plan.syncs_per_step = 0;
    return plan;
  }

  // What this backend's kernel does for one pass of the step plan.
  std::string pass_detail(Pass pass) const {
    const auto& m = *t_.model;
    const int32_t nlanes = t_.fast ? t_.fast->lanes() : kLanes;
    const std::string lanes = std::to_string(nlanes) + " " + precision() + " lanes";
    const std::string kernel = " (" + kernel_name() + " kernel)";
    const std::string tets_per_vertex = std::to_string(m.ntet()) + " tets gathered per vertex (" +
                                        std::to_string(m.layout.tets.item.size()) + " slots)";
    const std::string tet_batches = std::to_string(m.ntet()) + " tets evaluated once, " + std::to_string(nlanes) +
                                    " per batch, ";
    switch (pass) {
      case Pass::NodalPressure:
        return t_.fast ? std::to_string(m.ntet()) + " tets' 6 V_t read in pairs that share a face, " +
                             std::to_string(nlanes) +
                             " pairs per batch (2 fixed slices), a barrier, each point's "
                             "nodal volume and pressure, a barrier" + kernel
                       : "nodal volumes and pressures, " + tets_per_vertex + ", then a barrier";
      case Pass::ShearSmoothing:
        return "every point's stress on its node-averaged deformation gradient, " +
               (t_.fast ? "gathered over its spring slots, then a barrier" + kernel
                        : tets_per_vertex + ", then a barrier");
      case Pass::Springs:
        return std::to_string(m.nspring()) + " springs gathered from both ends (" +
               std::to_string(m.layout.springs.item.size()) + " slots)" + sutures_detail(m);
      case Pass::Volume:
        return t_.fast ? tet_batches + "into 2 fixed force slices" + kernel : tets_per_vertex;
      case Pass::ShearElement:
        return std::string(t_.plan.element == ElementTerm::SmoothedShear ? "smoothed " : "") +
               "shear element (neo-Hookean, no lambda" + (m.shear_damping_time > 0 ? ", with its damper" : "") + "), " +
               (t_.fast ? std::to_string(m.ntet()) + " tets in pairs that share a face, " + std::to_string(nlanes) +
                              " pairs per batch, into 2 fixed force slices" + kernel
                        : tets_per_vertex);
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
               " kernel)";      // Implicit Euler runs on its own backend (implicit_backend.h), never in this one's plan.
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
    if (t_.fast) {
      const Real *ux = t_.fast->displacement(0), *uy = t_.fast->displacement(1), *uz = t_.fast->displacement(2);
      for (size_t i = 0; i < out.size(); ++i) out[i] = t_.model->rest_position[i] + Vec3(ux[i], uy[i], uz[i]);
      return;
    }
    for (size_t i = 0; i < out.size(); ++i) out[i] = t_.model->rest_position[i] + displacement(u_, i);
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
    if (t_.fast) push_fast_state();
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
      reaction = t_.fast ? fast_step(ctx) : step(ctx);
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
  // Calls f(entry, p) for every slot of `table`, padding included, with the
  // point p whose lane holds it (chunk by chunk, no search per entry).
  template <class F>
  static void for_each_slot(const GatherTable& table, int32_t c, F f) {
    for (int32_t chunk = 0; chunk + 1 < static_cast<int32_t>(table.chunk_offset.size()); ++chunk)
      for (int32_t e = table.chunk_offset[chunk]; e < table.chunk_offset[chunk + 1]; ++e)
        f(e, chunk * c + (e - table.chunk_offset[chunk]) % c);
  }

  // Everything derived from `model`, in the backend's precision and slot
  // order; the constructor and prepare() share it, so a topology change needs
  // no code of its own here. Reads nothing of the run (state, time, thread
  // count): prepare() runs it on another thread while the backend ticks.
  Tables pack(const Model& model) const {
    Tables t;
    t.model = &model;
    t.plan = make_step_plan(model, tool_);
    const int32_t n = model.npoint();
    const auto& layout = model.layout;
    t.rest.assign(n, 0);
    for (int32_t i = 0; i < n; ++i) {
      t.rest.x[i] = static_cast<Real>(model.rest_position[i].x());
      t.rest.y[i] = static_cast<Real>(model.rest_position[i].y());
      t.rest.z[i] = static_cast<Real>(model.rest_position[i].z());
    }
    t.pos = t.rest;
    t.u_next.assign(n, 0);
    t.d_next.assign(n, 0);

    // Per-slot copies of the parameters in the backend's precision, one
    // contiguous stream per slot. Padding slots point at their own point
    // with zero stiffness: a zero-length spring and a flat tet add nothing,
    // so the loops need no branch. Rest lengths and volumes are recomputed
    // from the rounded rest positions exactly as the loops compute them, so
    // the rest state is force-free in either precision.
    const auto& springs = layout.springs;
    t.spring_other.resize(springs.item.size());
    t.spring_rest.assign(springs.item.size(), 0);
    t.spring_k.assign(springs.item.size(), 0);
    t.spring_d.assign(springs.item.size(), 0);
    t.suture_slots.clear();
    for_each_slot(springs, layout.chunk_size, [&](int32_t e, int32_t p) {
      const int32_t s = springs.item[e];
      t.spring_other[e] = s < 0 ? p : layout.spring_other[e];
      if (s < 0) return;
      t.spring_rest[e] = rest_distance(t.rest, p, t.spring_other[e]);
      t.spring_k[e] = static_cast<Real>(model.spring_k[s]);
      t.spring_d[e] = static_cast<Real>(model.spring_d[s]);
      if (s >= model.first_suture()) {
        // A suture: tension only, marked by a negative stiffness in its slot
        // (no extra stream for the loop to read); its rest length follows
        // the schedule (refresh_suture_rest).
        t.spring_k[e] = -t.spring_k[e];
        t.suture_slots.push_back({e, s});
      }
    });
    if (model.has_volume() || model.has_shear_element()) {
      const auto& tets = layout.tets;
      for (auto* v : {&t.tet_a, &t.tet_b, &t.tet_c}) v->resize(tets.item.size());
      // The nodal term reads only the vertices of each slot.
      const size_t per_tet = model.has_nodal_volume() ? 0 : tets.item.size();
      t.tet_rest.assign(per_tet, 0);
      t.tet_k.assign(model.has_shear_element() ? tets.item.size() : per_tet, 0);
      // The shear element: rest gradients g_a, g_b, g_c of each slot's
      // others (padding: zero, no force).
      for (auto& g : t.shear_g) g.assign(model.has_shear_element() ? tets.item.size() : 0, 0);
      for_each_slot(tets, layout.chunk_size, [&](int32_t e, int32_t p) {
        const int32_t tet = tets.item[e];
        const auto& o = layout.tet_others[e];
        t.tet_a[e] = tet < 0 ? p : o[0];
        t.tet_b[e] = tet < 0 ? p : o[1];
        t.tet_c[e] = tet < 0 ? p : o[2];
        if (tet < 0 || model.has_nodal_volume()) return;
        if (model.has_shear_element()) {
          for (int k = 0; k < 3; ++k)
            for (int axis = 0; axis < 3; ++axis)
              t.shear_g[3 * k + axis][e] = static_cast<Real>(shape_gradient_of(model, tet, o[k])[axis]);
          t.tet_k[e] = static_cast<Real>(model.tet_shear_k[tet]);
          return;
        }
        t.tet_rest[e] = rest_volume(t.rest, p, o[0], o[1], o[2]);
        t.tet_k[e] = static_cast<Real>(model.tet_k[tet]);
      });
    }
    t.mass.resize(n);
    t.inv_mass.resize(n);
    t.tool_scale.resize(n);
    for (int32_t i = 0; i < n; ++i) t.tool_scale[i] = static_cast<Real>(model.tool_scale(i));
    for (int32_t i = 0; i < n; ++i) {
      t.mass[i] = static_cast<Real>(model.mass[i]);
      t.inv_mass[i] = static_cast<Real>(model.inv_mass[i]);
    }
    // Slots per group of lanes: the widest point of the group.
    const int32_t groups_per_chunk = (layout.chunk_size + kLanes - 1) / kLanes;
    t.spring_width.assign(static_cast<size_t>(layout.nchunk) * groups_per_chunk, 0);
    t.tet_width.assign(t.spring_width.size(), 0);
    for (int32_t p = 0; p < n; ++p) {
      const int32_t c = p / layout.chunk_size, g = (p % layout.chunk_size) / kLanes;
      auto& sw = t.spring_width[c * groups_per_chunk + g];
      auto& tw = t.tet_width[c * groups_per_chunk + g];
      sw = std::max(sw, springs.count[p]);
      tw = std::max(tw, layout.tets.count[p]);
    }
    t.groups_per_chunk = groups_per_chunk;
    t.partial.resize(layout.nchunk);
    if (model.has_nodal_volume()) {
      // Rest nodal volumes by the very pass the step runs (t.pos is at rest
      // here), so the rest state is exactly pressure-free in either precision.
      t.node_k.resize(n);
      for (int32_t i = 0; i < n; ++i) t.node_k[i] = static_cast<Real>(model.point_volume_k[i]);
      t.node_rest.assign(n, 0);
      t.node_q.assign(n, 0);
      for (int32_t c = 0; c < layout.nchunk; ++c) nodal_volume_chunk(t, c, t.node_rest.data());
    } else {
      t.node_k.clear(), t.node_rest.clear(), t.node_q.clear();
    }
    // The smoothed shear element: 1/K_p per point (0 in no tet: its stress
    // stays P(I) = 0) and the stresses, rewritten every step.
    t.node_inv_k.clear();
    for (auto& a : t.node_stress) a.assign(model.has_smoothed_shear() ? n : 0, 0);
    if (model.has_smoothed_shear()) {
      t.node_inv_k.resize(n);
      for (int32_t i = 0; i < n; ++i)
        t.node_inv_k[i] = model.point_shear_k[i] > 0 ? static_cast<Real>(1 / model.point_shear_k[i]) : Real(0);
    }
    t.smoothed_share = static_cast<Real>(model.shear_smoothed_share);
    pack_fast(t);
    if (t.plan.tool == ToolTerm::Surface) t.surface.pack(model, t.tool_scale, t.tool_scale.size(), tool_.hertz_layer);
    return t;
  }

  // The surface-contact pass at this substep's positions (X + u): the
  // kernels' tool pass then adds its per-point forces.
  void surface_contact(KernelStepInputs<Real>& ctx, const ToolPlacement& placed) {
    const std::array<const Real*, 3> rest = {t_.rest.x.data(), t_.rest.y.data(), t_.rest.z.data()};
    const std::array<const Real*, 3> u =
        t_.fast ? std::array<const Real*, 3>{t_.fast->displacement(0), t_.fast->displacement(1), t_.fast->displacement(2)}
                : std::array<const Real*, 3>{u_.x.data(), u_.y.data(), u_.z.data()};
    t_.surface.evaluate(rest, u, placed, ctx.tool_k, tool_.friction, threads_);
    ctx.contact_slot = t_.surface.slot();
    ctx.contact_force = t_.surface.force();
  }

  // Sutures tighten on their schedule: rest lengths at the start of the tick,
  // constant over its substeps. The few suture slots only; nothing allocates.
  void refresh_suture_rest() {
    for (const auto& [e, s] : t_.suture_slots) {
      t_.spring_rest[e] = static_cast<Real>(t_.model->spring_rest_at(s, time_));
      if (t_.fast) t_.fast->set_spring_rest(e, t_.spring_rest[e]);
    }
  }

  // The simd kernel packs its own streams from the same Model; while it
  // runs, it holds the state (u_, d_ are filled from it only for a rebuild;
  // install() puts the state in).
  void pack_fast(Tables& t) const {
    if (kernel_choice_ == CpuKernel::Generic) return;
    const std::string refusal = simd_kernel_unsupported(t.plan, t.model->layout.chunk_size, simd_target_);
    if (!refusal.empty() && kernel_choice_ == CpuKernel::Simd)
      throw Error(ErrorKind::Backend, "cpu backend: the simd kernel cannot run this model: " + refusal);
    if (!refusal.empty()) return;
    t.fast = make_simd_kernel<Real>(simd_target_);
    t.fast->pack(*t.model, t.plan);
    t.fast_partial.resize(t.fast->nchunk());
    // Padding lanes (at the origin, no mass) may fall inside a push tool: scale 0.
    t.tool_scale.resize(std::max(t.tool_scale.size(), npad_of(t)), 0);
  }
  // Points the simd kernel reads a register at a time, padding included (0 without it).
  static size_t npad_of(const Tables& t) {
    return t.fast ? static_cast<size_t>(t.fast->nchunk()) * t.model->layout.chunk_size : 0;
  }
  // Makes t_ (just packed) the tables the backend steps: the state u_, d_
  // (npoint of t_.model) into its kernel, the sutures' rest lengths at time_.
  void install() {
    // The kernel reads attachment indices a register of points at a time, padding included.
    attached_.resize(std::max(attached_.size(), npad_of(t_)), -1);
    refresh_suture_rest();
    if (t_.fast) push_fast_state();
  }
  void push_fast_state() {
    for (size_t i = 0; i < u_.x.size(); ++i) {
      const Real u[3] = {u_.x[i], u_.y[i], u_.z[i]}, d[3] = {d_.x[i], d_.y[i], d_.z[i]};
      t_.fast->set_point(static_cast<int32_t>(i), u, d);
    }
  }
  void pull_fast_state() {
    Real u[3], d[3];
    for (size_t i = 0; i < u_.x.size(); ++i) {
      t_.fast->get_point(static_cast<int32_t>(i), u, d);
      u_.x[i] = u[0], u_.y[i] = u[1], u_.z[i] = u[2];
      d_.x[i] = d[0], d_.y[i] = d[1], d_.z[i] = d[2];
    }
  }

  Reaction fast_step(const KernelStepInputs<Real>& in) {
    t_.fast->step(in, threads_, t_.fast_partial);
    Reaction reaction;
    if (in.tool != ToolTerm::None) {
      // Fixed-order sum of per-chunk partials: identical for any thread count.
      for (const ChunkReaction& p : t_.fast_partial) {
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
               for (int32_t s = 0; s < steps; ++s) t_.fast ? fast_step(ctx) : step(ctx);
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
    if (t_.fast) push_fast_state();
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
  static Real rest_distance(const Soa3<Real>& rest, int32_t p, int32_t q) {
    const Real dx = rest.x[q] - rest.x[p], dy = rest.y[q] - rest.y[p], dz = rest.z[q] - rest.z[p];
    return std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  static Real rest_volume(const Soa3<Real>& rest, int32_t p, int32_t a, int32_t b, int32_t c) {
    auto d = [&](int32_t q, const std::vector<Real>& v) { return v[q] - v[p]; };
    const Real ax = d(a, rest.x), ay = d(a, rest.y), az = d(a, rest.z);
    const Real bx = d(b, rest.x), by = d(b, rest.y), bz = d(b, rest.z);
    const Real cx = d(c, rest.x), cy = d(c, rest.y), cz = d(c, rest.z);
    return (ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)) / Real(6);
  }

  // Each combination of the plan's passes is its own compiled loop, so a
  // lean scene never touches the code or data of a pass it lacks.
  Reaction step(const KernelStepInputs<Real>& ctx) {
    switch (t_.plan.element) {
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
    return t_.plan.gravity ? dispatch_tool<Volume, true>(ctx) : dispatch_tool<Volume, false>(ctx);
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
    const int32_t nchunk = t_.model->layout.nchunk, npoint = t_.model->npoint();
#pragma omp parallel num_threads(threads_)
    {
      // Positions x = X + u once per step: the gathers below then fetch 3
      // coordinates per neighbour instead of 6. Integration stays on u and d.
#pragma omp for simd schedule(static)
      for (int32_t p = 0; p < npoint; ++p) {
        t_.pos.x[p] = t_.rest.x[p] + u_.x[p];
        t_.pos.y[p] = t_.rest.y[p] + u_.y[p];
        t_.pos.z[p] = t_.rest.z[p] + u_.z[p];
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
    u_.swap(t_.u_next);  // u_t <- u_{t+1}
    d_.swap(t_.d_next);  // d_t <- d_{t+1}
    Reaction reaction;
    if constexpr (Tool != ToolTerm::None) {
      // Fixed-order sum of per-chunk partials: identical for any thread count.
      for (const ChunkReaction& p : t_.partial) {
        reaction.force += p.force;
        reaction.torque += p.torque;
        reaction.contacts += p.contacts;
      }
    }
    return reaction;
  }

  // Nodal volumes V_p = sum over the tets of p of V_t / 4 at t_.pos, for the
  // points of chunk c, into out. Not inlined: pack() and the step must run
  // the same instructions so the rest state gives exactly V_p^r.
  __attribute__((noinline)) static void nodal_volume_chunk(const Tables& t, int32_t c, Real* __restrict out) {
    const auto& L = t.model->layout;
    const int32_t C = L.chunk_size;
    const int32_t first = c * C, last = std::min(t.model->npoint(), first + C);
    const Real* __restrict X = t.pos.x.data();
    const Real* __restrict Y = t.pos.y.data();
    const Real* __restrict Z = t.pos.z.data();
    const int32_t* __restrict ta = t.tet_a.data();
    const int32_t* __restrict tb = t.tet_b.data();
    const int32_t* __restrict tc = t.tet_c.data();
    for (int32_t g0 = first; g0 < last; g0 += kLanes) {
      const int32_t lanes = std::min(kLanes, last - g0);
      const int32_t lane0 = g0 - first;
      const int32_t group = c * t.groups_per_chunk + lane0 / kLanes;
      alignas(64) Real v[kLanes] = {};
      for (int32_t j = 0; j < t.tet_width[group]; ++j) {
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

  // Nodal pressures q_p = k_p (V_p - V_p^r) of chunk c into t_.node_q.
  void nodal_pressure_chunk(int32_t c) {
    nodal_volume_chunk(t_, c, t_.node_q.data());
    const int32_t first = c * t_.model->layout.chunk_size;
    const int32_t last = std::min(t_.model->npoint(), first + t_.model->layout.chunk_size);
#pragma omp simd
    for (int32_t p = first; p < last; ++p) t_.node_q[p] = force_law::volume_pressure(t_.node_k[p], t_.node_q[p], t_.node_rest[p]);
  }

  // The smoothed shear element's stress P(Fbar_p) = Fbar + phi'(J) cof Fbar
  // of the points of chunk c into t_.node_stress (row-major), with
  // Fbar_p - I = sum over p's tet slots of k_t H_t / K_p and H_t = sum over
  // the others q of (u_q - u_p) g_q^T, from displacements as in the force
  // pass: at rest H = 0 exactly, Fbar = I and P = 0 in either precision.
  void shear_stress_chunk(int32_t c) {
    const auto& L = t_.model->layout;
    const int32_t C = L.chunk_size;
    const int32_t first = c * C, last = std::min(t_.model->npoint(), first + C);
    const Real* __restrict ux = u_.x.data();
    const Real* __restrict uy = u_.y.data();
    const Real* __restrict uz = u_.z.data();
    const int32_t* __restrict ta = t_.tet_a.data();
    const int32_t* __restrict tb = t_.tet_b.data();
    const int32_t* __restrict tc = t_.tet_c.data();
    const Real* __restrict kt = t_.tet_k.data();
    const std::array<const Real*, 9> g = {t_.shear_g[0].data(), t_.shear_g[1].data(), t_.shear_g[2].data(),
                                          t_.shear_g[3].data(), t_.shear_g[4].data(), t_.shear_g[5].data(),
                                          t_.shear_g[6].data(), t_.shear_g[7].data(), t_.shear_g[8].data()};
    for (int32_t g0 = first; g0 < last; g0 += kLanes) {
      const int32_t lanes = std::min(kLanes, last - g0);
      const int32_t lane0 = g0 - first;
      const int32_t group = c * t_.groups_per_chunk + lane0 / kLanes;
      alignas(64) Real h[9][kLanes] = {};
      for (int32_t j = 0; j < t_.tet_width[group]; ++j) {
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
        const Real w = t_.node_inv_k[p];
        const Real f00 = 1 + w * h[0][l], f01 = w * h[1][l], f02 = w * h[2][l];
        const Real f10 = w * h[3][l], f11 = 1 + w * h[4][l], f12 = w * h[5][l];
        const Real f20 = w * h[6][l], f21 = w * h[7][l], f22 = 1 + w * h[8][l];
        const Real k00 = f11 * f22 - f12 * f21, k01 = f12 * f20 - f10 * f22, k02 = f10 * f21 - f11 * f20;
        const Real k10 = f02 * f21 - f01 * f22, k11 = f00 * f22 - f02 * f20, k12 = f01 * f20 - f00 * f21;
        const Real k20 = f01 * f12 - f02 * f11, k21 = f02 * f10 - f00 * f12, k22 = f00 * f11 - f01 * f10;
        const Real slope = force_law::shear_barrier_slope(f00 * k00 + f01 * k01 + f02 * k02);
        t_.node_stress[0][p] = f00 + slope * k00;
        t_.node_stress[1][p] = f01 + slope * k01;
        t_.node_stress[2][p] = f02 + slope * k02;
        t_.node_stress[3][p] = f10 + slope * k10;
        t_.node_stress[4][p] = f11 + slope * k11;
        t_.node_stress[5][p] = f12 + slope * k12;
        t_.node_stress[6][p] = f20 + slope * k20;
        t_.node_stress[7][p] = f21 + slope * k21;
        t_.node_stress[8][p] = f22 + slope * k22;
      }
    }
  }

  template <ElementTerm Volume, bool Gravity, ToolTerm Tool>
  void chunk(const KernelStepInputs<Real>& ctx, int32_t c) {
    const auto& L = t_.model->layout;
    const int32_t C = L.chunk_size;
    const int32_t first = c * C, last = std::min(t_.model->npoint(), first + C);
    ChunkReaction partial;
    const Real* __restrict X = t_.pos.x.data();
    const Real* __restrict Y = t_.pos.y.data();
    const Real* __restrict Z = t_.pos.z.data();
    const Real* __restrict ux = u_.x.data();
    const Real* __restrict uy = u_.y.data();
    const Real* __restrict uz = u_.z.data();
    const Real* __restrict dx = d_.x.data();
    const Real* __restrict dy = d_.y.data();
    const Real* __restrict dz = d_.z.data();
    for (int32_t g0 = first; g0 < last; g0 += kLanes) {
      const int32_t lanes = std::min(kLanes, last - g0);
      const int32_t lane0 = g0 - first;
      const int32_t group = c * t_.groups_per_chunk + lane0 / kLanes;
      alignas(64) Real fx[kLanes], fy[kLanes], fz[kLanes];
#pragma omp simd
      for (int32_t l = 0; l < lanes; ++l) {
        const int32_t p = g0 + l;
        fx[l] = Gravity ? t_.mass[p] * ctx.gravity[0] : Real(0);
        fy[l] = Gravity ? t_.mass[p] * ctx.gravity[1] : Real(0);
        fz[l] = Gravity ? t_.mass[p] * ctx.gravity[2] : Real(0);
      }

      // Springs + dampers: f = [k (L - r) + d (dv . l/L)] l/L, l = x_q - x_p.
      // A suture (k < 0 in its slot, stiffness |k|) pulls only: no force while
      // slack (L <= r), and a closing damper never turns the pull into a push.
      const int32_t* __restrict other = t_.spring_other.data();
      const Real* __restrict rest = t_.spring_rest.data();
      const Real* __restrict k = t_.spring_k.data();
      const Real* __restrict d = t_.spring_d.data();
      for (int32_t j = 0; j < t_.spring_width[group]; ++j) {
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
        const int32_t* __restrict ta = t_.tet_a.data();
        const int32_t* __restrict tb = t_.tet_b.data();
        const int32_t* __restrict tc = t_.tet_c.data();
        const Real* __restrict kt = t_.tet_k.data();
        const Real* __restrict gax = t_.shear_g[0].data();
        const Real* __restrict gay = t_.shear_g[1].data();
        const Real* __restrict gaz = t_.shear_g[2].data();
        const Real* __restrict gbx = t_.shear_g[3].data();
        const Real* __restrict gby = t_.shear_g[4].data();
        const Real* __restrict gbz = t_.shear_g[5].data();
        const Real* __restrict gcx = t_.shear_g[6].data();
        const Real* __restrict gcy = t_.shear_g[7].data();
        const Real* __restrict gcz = t_.shear_g[8].data();
        // Smoothed: the per-tet stress weighs 1 - s, the mean of the four
        // corners' smoothed stresses s (their sum times s / 4).
        constexpr bool smoothed = Volume == ElementTerm::SmoothedShear;
        const Real per_tet = smoothed ? 1 - t_.smoothed_share : Real(1), corners = smoothed ? t_.smoothed_share / 4 : Real(0);
        const std::array<const Real*, 9> P = {t_.node_stress[0].data(), t_.node_stress[1].data(), t_.node_stress[2].data(),
                                              t_.node_stress[3].data(), t_.node_stress[4].data(), t_.node_stress[5].data(),
                                              t_.node_stress[6].data(), t_.node_stress[7].data(), t_.node_stress[8].data()};
        for (int32_t j = 0; j < t_.tet_width[group]; ++j) {
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
        const Real* __restrict q = t_.node_q.data();
        const int32_t* __restrict ta = t_.tet_a.data();
        const int32_t* __restrict tb = t_.tet_b.data();
        const int32_t* __restrict tc = t_.tet_c.data();
        const Real* __restrict vr = t_.tet_rest.data();
        const Real* __restrict kv = t_.tet_k.data();
        for (int32_t j = 0; j < t_.tet_width[group]; ++j) {
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
      Real* __restrict nx = t_.u_next.x.data();
      Real* __restrict ny = t_.u_next.y.data();
      Real* __restrict nz = t_.u_next.z.data();
      Real* __restrict ndx = t_.d_next.x.data();
      Real* __restrict ndy = t_.d_next.y.data();
      Real* __restrict ndz = t_.d_next.z.data();
#pragma omp simd
      for (int32_t l = 0; l < lanes; ++l) {
        const int32_t p = g0 + l;
        const Real w = t_.inv_mass[p] * ctx.dt2;
        const bool free = t_.inv_mass[p] > Real(0);
        ndx[p] = free ? ctx.drag * dx[p] + w * fx[l] : Real(0);
        ndy[p] = free ? ctx.drag * dy[p] + w * fy[l] : Real(0);
        ndz[p] = free ? ctx.drag * dz[p] + w * fz[l] : Real(0);
        nx[p] = ux[p] + ndx[p];
        ny[p] = uy[p] + ndy[p];
        nz[p] = uz[p] + ndz[p];
      }
    }
    if constexpr (Tool != ToolTerm::None) t_.partial[c] = partial;
  }

  BackendTool tool_;
  CpuKernel kernel_choice_;
  SimdTarget simd_target_;  // the simd kernel's target
  int threads_;
  StepTiming timing_;                     // stands in for the clock in tests (thread choice)
  std::optional<ThreadChoice> choice_;    // set when the thread count is chosen by timing
  double live_share_ = 0;                 // CpuBackendOptions::live_share
  std::string device_;
  double time_ = 0;
  // The state: with the simd kernel it lives in t_.fast, and these hold
  // it only across a rebuild.
  Soa3<Real> u_;  // displacements from rest at t (npoint)
  Soa3<Real> d_;  // step increments u_t - u_{t-1} (npoint)
  std::vector<int32_t> attached_;  // attachment index per point or -1 (npoint; npad for the simd kernel)
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
