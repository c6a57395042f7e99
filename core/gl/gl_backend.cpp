#include "core/gl/gl_backend.h"

#include <EGL/egl.h>

#include <cstddef>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>

#include "core/gl/gl_model_pack.h"
#include "core/physics/force_law.h"
#include "core/sim/contact_plan.h"
#include "core/util/error.h"
#include "shaders/bindings.glsl.h"

namespace organsim {
namespace {

constexpr int kSlots = ORGANSIM_GL_READBACK_SLOTS;
constexpr uint32_t kNoPoint = 0xFFFFFFFFu;  // status slot value: every position finite
constexpr GLuint64 kReadbackTimeoutNs = 10'000'000'000ull;  // a tick taking 10 s is a hung device

// An immutable-storage buffer on the current context (16 bytes for an empty
// table: zero-sized storage is an error in GL).
GLuint make_buffer(const char* what, size_t bytes, const void* data, GLbitfield flags) {
  GLuint buffer = 0;
  glCreateBuffers(1, &buffer);
  const size_t size = bytes > 0 ? bytes : 16;
  glNamedBufferStorage(buffer, static_cast<GLsizeiptr>(size), bytes > 0 ? data : nullptr, flags);
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    glDeleteBuffers(1, &buffer);
    throw Error(ErrorKind::Backend, std::string("GL backend: glNamedBufferStorage(") + what + ", " +
                                        std::to_string(size) + " bytes) failed, error " + std::to_string(error));
  }
  return buffer;
}

// `value` as a GLSL float literal that rounds to the same float.
std::string float_literal(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9e", static_cast<double>(static_cast<float>(value)));
  return text;
}

}  // namespace

GlBackend::GlBackend(const Model& model, const BackendTool& tool, const GlBackendOptions& options)
    : model_(&model), tool_(tool), options_(options) {
  gl::EglContextOptions context_options;
  context_options.debug = options.debug;
  context_ = std::make_unique<gl::EglContext>(context_options);

  plan_ = make_step_plan(model, tool);
  const bool nodal = plan_.has(Pass::NodalPressure), smoothed = plan_.has(Pass::ShearSmoothing);

  // Lean scenes: step.comp is compiled with the plan's passes only, so code
  // for absent physics is not in the shader.
  std::vector<std::string> defines;
  if (plan_.has(Pass::Volume)) defines.push_back("HAS_VOLUME");
  if (nodal) defines.push_back("NODAL_VOLUME");
  if (plan_.has(Pass::ShearElement)) defines.push_back("SHEAR_ELEMENT");
  // The share s as a float literal (max_digits10: the same float as the CPU's).
  if (smoothed) defines.push_back("SMOOTHED_SHEAR " + float_literal(model.shear_smoothed_share));
  if (plan_.has(Pass::Gravity)) defines.push_back("HAS_GRAVITY");
  if (plan_.tool == ToolTerm::Push) defines.push_back("TOOL_PUSH");
  if (plan_.tool == ToolTerm::Pull) defines.push_back("TOOL_PULL");
  if (plan_.tool == ToolTerm::Surface) defines.push_back("TOOL_SURFACE");
  if (plan_.tool == ToolTerm::Surface && tool.shape == ToolShape::Grasper) defines.push_back("GRASPER");
  if (plan_.tool == ToolTerm::Surface && tool.friction.on()) defines.push_back("FRICTION");
  const bool layered = plan_.tool == ToolTerm::Surface && tool.hertz_layer;
  if (layered) defines.push_back("HERTZ_LAYER");
  if (options.record_forces) defines.push_back("RECORD_FORCE");
  if (options.threads_per_point < 0 || options.threads_per_point > 16) {
    // 16 x 64 = 1024 invocations, the largest workgroup every GL 4.5 driver must run.
    throw Error(ErrorKind::Usage, "GL backend: threads per point must be 0 (automatic) or 1 to 16 (got " +
                                      std::to_string(options.threads_per_point) + ")");
  }
  threads_per_point_ = options.threads_per_point > 0 ? options.threads_per_point : context_->software() ? 1 : 8;
  const std::string split = "THREADS_PER_POINT " + std::to_string(threads_per_point_);
  defines.push_back(split);
  step_ = gl::ComputeProgram("step.comp", defines);
  if (tool.present) reduce_ = gl::ComputeProgram("reduce_reaction.comp", {});
  if (nodal) nodal_pressure_ = gl::ComputeProgram("nodal_pressure.comp", {split});
  carry_ = gl::ComputeProgram("carry_state.comp", {});
  if (smoothed) shear_smoothing_ = gl::ComputeProgram("shear_smoothing.comp", {split});
  if (layered) {
    hertz_layer_touch_ = gl::ComputeProgram("hertz_layer_touch.comp", {});
    hertz_layer_ = gl::ComputeProgram("hertz_layer.comp", {});
    for (GLuint program : {hertz_layer_touch_.id(), hertz_layer_.id()})
      glProgramUniform1f(program, ORGANSIM_GL_U_TOOL_RADIUS, static_cast<float>(tool.radius));
    glProgramUniform1f(hertz_layer_touch_.id(), ORGANSIM_GL_U_TOOL_K, static_cast<float>(tool.contact_stiffness));
    glProgramUniform1f(hertz_layer_.id(), ORGANSIM_GL_U_LAYER_FACTOR,
                       static_cast<float>(force_law::kHertzLayerPunchFactor));
    glProgramUniform1f(hertz_layer_.id(), ORGANSIM_GL_U_LAYER_LINE_FACTOR,
                       static_cast<float>(force_law::kLineLayerHalfWidthFactor));
    // The solve's result, read by step.comp: one vec4, the same for every Model version.
    const float none[4] = {0, 0, 1, 0};
    layer_out_ = create_buffer("Hertz layer {n, delta}", sizeof none, none, 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_LAYER_OUT, layer_out_);
  }

  // Buffers that do not depend on the model's size: the readback rings.
  const GLbitfield map = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
  if (tool.present) {
    // Written by the GPU, read by the CPU one tick later without a copy.
    const size_t ring = static_cast<size_t>(kSlots) * 8 * sizeof(float);
    reaction_ = create_buffer("reaction ring (mapped)", ring, nullptr, map);
    reaction_map_ = static_cast<const float*>(glMapNamedBufferRange(reaction_, 0, static_cast<GLsizeiptr>(ring), map));
    if (!reaction_map_) {
      throw Error(ErrorKind::Backend, "GL backend: glMapNamedBufferRange(reaction ring, persistent coherent) failed");
    }
  }
  {
    // Blow-up flag per ring slot, read with the reaction; cleared on the GPU
    // (glClearNamedBufferSubData) before the tick that writes it.
    const std::vector<uint32_t> none(kSlots, kNoPoint);
    status_ = create_buffer("non-finite flag ring (mapped)", none.size() * sizeof(uint32_t), none.data(), map);
    status_map_ = static_cast<const uint32_t*>(
        glMapNamedBufferRange(status_, 0, static_cast<GLsizeiptr>(none.size() * sizeof(uint32_t)), map));
    if (!status_map_) {
      throw Error(ErrorKind::Backend, "GL backend: glMapNamedBufferRange(status ring, persistent coherent) failed");
    }
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_STATUS, status_);
  if (reaction_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_REACTION, reaction_);
  ring_buffers_ = buffer_sizes_.size();
  slots_.assign(kSlots, Slot{});

  // x_t = rest, d_t = 0.
  const gl::PackedModel packed = gl::pack_model(model, layered);
  const std::vector<float> zero(packed.rest.size(), 0.0f);
  install(create_tables(packed, plan_), packed, packed.rest.data(), zero.data());
  // One empty carry now: a driver may compile a program at its first
  // dispatch (llvmpipe does), which would otherwise fall on a cut's tick.
  carry(x_[0], d_[0], x_[0], 0, 0);
  if (plan_.gravity) {
    glProgramUniform3f(step_.id(), ORGANSIM_GL_U_GRAVITY, static_cast<float>(model.gravity.x()),
                       static_cast<float>(model.gravity.y()), static_cast<float>(model.gravity.z()));
  }
  if (tool.present) {
    glProgramUniform1f(step_.id(), ORGANSIM_GL_U_TOOL_RADIUS, static_cast<float>(tool.radius));
    glProgramUniform1f(step_.id(), ORGANSIM_GL_U_TOOL_K, static_cast<float>(tool.contact_stiffness));
  }
  if (anchors_)
    glProgramUniform2f(step_.id(), ORGANSIM_GL_U_FRICTION, static_cast<float>(tool.friction.mu_s),
                       static_cast<float>(tool.friction.mu_k));
  context_->check_errors("GL backend setup");
}

GlBackend::Tables GlBackend::create_tables(const gl::PackedModel& packed, const StepPlan& plan) const {
  Tables t;
  auto make = [&](const char* what, size_t bytes, const void* data, GLbitfield flags) {
    const GLuint b = make_buffer(what, bytes, data, flags);
    t.sizes.emplace_back(what, bytes > 0 ? bytes : 16);
    return b;
  };
  const size_t npad = static_cast<size_t>(packed.npad);
  t.mass = make("mass {1/m, m, tool k scale, 0}", packed.mass.size() * sizeof(float), packed.mass.data(), 0);
  t.chunks = make("chunks", packed.chunks.size() * sizeof(int32_t), packed.chunks.data(), 0);
  // Sutures' rest lengths are rewritten per tick (refresh_suture_rest).
  t.springs = make("spring entries {other, rest, k, d}", packed.springs.size() * sizeof(gl::SpringEntry),
                   packed.springs.data(), packed.suture_entries.empty() ? 0 : GL_DYNAMIC_STORAGE_BIT);
  if (plan.volume() || plan.shear()) {
    t.tets = make("tet entries {a, b, c, k_v, V_r}", packed.tets.size() * sizeof(gl::TetEntry), packed.tets.data(), 0);
  }
  if (plan.shear()) {
    t.rest = make("rest positions", packed.rest.size() * sizeof(float), packed.rest.data(), 0);
    t.shear_params = make("shear element entries {g_a k_t, g_b d_t, g_c w}",
                          packed.shear.size() * sizeof(gl::ShearEntry), packed.shear.data(), 0);
  }
  if (plan.element == ElementTerm::NodalVolume) {
    t.nodal_params = make("nodal {k_a, V_a^r}", packed.nodal.size() * sizeof(float), packed.nodal.data(), 0);
    t.pressure = make("nodal pressures", npad * sizeof(float), nullptr, 0);
  }
  if (plan.element == ElementTerm::SmoothedShear) {
    t.shear_stress = make("smoothed shear stress P(Fbar) (3 vec4 per point)", npad * 12 * sizeof(float), nullptr, 0);
  }
  if (plan.tool == ToolTerm::Surface) {
    t.surface_range = make("surface triangles per point {first, count}", packed.surface_range.size() * sizeof(int32_t),
                           packed.surface_range.data(), 0);
    // An empty surface still needs a buffer to bind: one unused entry.
    const std::vector<int32_t> none(4, 0);
    const auto& entries = packed.surface_entries.empty() ? none : packed.surface_entries;
    t.surface_tris =
        make("surface triangle entries {corners, which}", entries.size() * sizeof(int32_t), entries.data(), 0);
  }
  if (!packed.layer_tris.empty()) {
    t.layer_ntri = static_cast<int32_t>(packed.layer_tris.size());
    t.layer_tris = make("Hertz layer triangles {corners, a_h, E*}", packed.layer_tris.size() * sizeof(gl::LayerTri),
                        packed.layer_tris.data(), 0);
    t.layer_touch =
        make("Hertz layer penalties {f_t, k_t}, {s_t, 0, 0, 0}", packed.layer_tris.size() * 8 * sizeof(float), nullptr, 0);
    t.layer_blocks = make("Hertz layer triangles touching per block", gl::layer_blocks(packed) * sizeof(uint32_t),
                          nullptr, 0);
  }
  if (tool_.present) {
    t.partials =
        make("reaction partials per workgroup", static_cast<size_t>(packed.nchunk) * 8 * sizeof(float), nullptr, 0);
  }
  if (options_.record_forces) t.force = make("recorded forces", npad * 4 * sizeof(float), nullptr, 0);
  return t;
}

void GlBackend::install(Tables tables, const gl::PackedModel& packed, const float* x, const float* d) {
  npoint_ = packed.npoint;
  nchunk_ = packed.nchunk;
  npad_ = packed.npad;
  buffer_sizes_.resize(ring_buffers_);
  // Two pairs of buffers swapped after each substep.
  const size_t xbytes = packed.rest.size() * sizeof(float);
  cur_ = 0;
  x_[0] = create_buffer("x_t", xbytes, x, GL_DYNAMIC_STORAGE_BIT);
  x_[1] = create_buffer("x_{t+1}", xbytes, x, GL_DYNAMIC_STORAGE_BIT);
  d_[0] = create_buffer("x_t - x_{t-1}", xbytes, d, GL_DYNAMIC_STORAGE_BIT);
  d_[1] = create_buffer("x_{t+1} - x_t", xbytes, d, GL_DYNAMIC_STORAGE_BIT);
  mass_ = tables.mass, chunks_ = tables.chunks, springs_ = tables.springs, tets_ = tables.tets, rest_ = tables.rest;
  shear_params_ = tables.shear_params, nodal_params_ = tables.nodal_params, pressure_ = tables.pressure;
  shear_stress_ = tables.shear_stress, surface_range_ = tables.surface_range, surface_tris_ = tables.surface_tris;
  partials_ = tables.partials, force_ = tables.force;
  layer_tris_ = tables.layer_tris, layer_touch_ = tables.layer_touch, layer_blocks_ = tables.layer_blocks;
  layer_nblock_ = gl::layer_blocks(packed);
  for (GLuint program : {hertz_layer_touch_.id(), hertz_layer_.id()})
    if (program) glProgramUniform1i(program, ORGANSIM_GL_U_LAYER_TRIS, tables.layer_ntri);
  buffer_sizes_.insert(buffer_sizes_.end(), tables.sizes.begin(), tables.sizes.end());
  suture_entries_ = packed.suture_entries;
  suture_rest_.assign(suture_entries_.size(), -1.0f);
  if (plan_.tool == ToolTerm::Pull) {
    // Attachments survive a rebuild: the ids they name are kept.
    attach_upload_.resize(static_cast<size_t>(npad_) * 4, 0.0f);
    attach_ = create_buffer("attachments {offset, attached}", attach_upload_.size() * sizeof(float),
                            attach_upload_.data(), GL_DYNAMIC_STORAGE_BIT);
  }
  if (plan_.tool == ToolTerm::Surface && tool_.friction.on()) {
    // None anchored; a rebuild copies the old points' anchors in on the GPU
    // (they are per point id, which it keeps: a grip holds through a cut).
    anchors_ = create_buffer("friction anchors {in the tool frame, anchored}", static_cast<size_t>(npad_) * 4 * sizeof(float),
                             nullptr, 0);
    glClearNamedBufferData(anchors_, GL_R32F, GL_RED, GL_FLOAT, nullptr);
  }
  if (tool_.present) glProgramUniform1i(reduce_.id(), ORGANSIM_GL_U_NPARTIAL, nchunk_);
  if (options_.keep_reaction_positions) {
    // Written by a GPU copy at each tick's end, read by the CPU after that tick's fence.
    const GLbitfield map = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
    const size_t ring = static_cast<size_t>(kSlots) * xbytes;
    reaction_x_ = create_buffer("end positions per ring slot (mapped)", ring, nullptr, map);
    reaction_x_map_ = static_cast<const float*>(glMapNamedBufferRange(reaction_x_, 0, static_cast<GLsizeiptr>(ring), map));
    if (!reaction_x_map_) {
      throw Error(ErrorKind::Backend, "GL backend: glMapNamedBufferRange(end positions ring, persistent coherent) failed");
    }
  }
  readback_.resize(static_cast<size_t>(npad_) * 4);

  // Bindings that never change until the next rebuild; the position buffers
  // rotate per substep.
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_MASS, mass_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_CHUNKS, chunks_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_SPRINGS, springs_);
  if (tets_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_TETS, tets_);
  if (nodal_params_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_NODAL, nodal_params_);
  if (pressure_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_PRESSURE, pressure_);
  if (rest_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_REST, rest_);
  if (shear_params_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_SHEAR, shear_params_);
  if (shear_stress_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_SHEAR_STRESS, shear_stress_);
  if (attach_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_ATTACH, attach_);
  if (surface_range_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_SURFACE, surface_range_);
  if (surface_tris_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_SURFACE_TRIS, surface_tris_);
  if (anchors_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_ANCHOR, anchors_);
  if (partials_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_PARTIALS, partials_);
  if (force_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_FORCE, force_);
  if (layer_tris_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_LAYER_TRIS, layer_tris_);
  if (layer_touch_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_LAYER_TOUCH, layer_touch_);
  if (layer_blocks_) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_LAYER_BLOCKS, layer_blocks_);
}

void GlBackend::delete_model_buffers() {
  if (reaction_x_map_) glUnmapNamedBuffer(reaction_x_);
  reaction_x_map_ = nullptr;
  if (reaction_x_) glDeleteBuffers(1, &reaction_x_);
  reaction_x_ = 0;
  for (GLuint* b : {&x_[0], &x_[1], &d_[0], &d_[1], &mass_, &chunks_, &springs_, &tets_, &nodal_params_, &pressure_, &rest_, &shear_params_, &shear_stress_, &attach_, &surface_range_, &surface_tris_, &anchors_, &partials_, &force_, &layer_tris_, &layer_touch_, &layer_blocks_}) {
    if (*b) glDeleteBuffers(1, b);
    *b = 0;
  }
}

std::vector<GLuint> GlBackend::Tables::buffers() const {
  std::vector<GLuint> out;
  for (GLuint b : {mass, chunks, springs, tets, rest, shear_params, nodal_params, pressure, shear_stress, surface_range,
                   surface_tris, partials, force, layer_tris, layer_touch, layer_blocks})
    if (b) out.push_back(b);
  return out;
}

// What GlBackend::prepare hands to adopt: the host-side arrays, the step's
// passes and the tables already on the device. Dropped without an adopt(),
// it hands its buffers back to the backend to delete on its own context
// (so it must not outlive the backend that made it).
struct GlBackend::Prepared final : PreparedModel {
  Prepared(const Model& next, const BackendTool& tool, const GlBackend& owner)
      : PreparedModel(next),
        packed(gl::pack_model(next, tool.hertz_layer)),
        plan(make_step_plan(next, tool)),
        owner(&owner) {}
  ~Prepared() override {
    if (tables) owner->discard(tables->buffers());
  }
  gl::PackedModel packed;
  StepPlan plan;
  std::optional<Tables> tables;
  const GlBackend* owner;
};

std::unique_ptr<PreparedModel> GlBackend::prepare(const Model& next) const {
  auto prepared = std::make_unique<Prepared>(next, tool_, *this);
  // The tables go up on a context of their own that shares objects with the
  // backend's, so that on the worker thread the upload costs the ticks
  // nothing (at 28k points it is most of a rebuild: 6 ms on llvmpipe). The
  // calling thread's context is restored after, for a prepare() on the loop.
  std::lock_guard<std::mutex> lock(upload_mutex_);
  const EGLDisplay display = eglGetCurrentDisplay();
  const EGLContext previous = eglGetCurrentContext();
  if (!upload_context_) {
    gl::EglContextOptions o;
    o.debug = options_.debug;
    o.share = context_.get();
    upload_context_ = std::make_unique<gl::EglContext>(o);  // current on this thread
  } else {
    upload_context_->make_current();
  }
  const auto restore = [&] {
    if (previous != EGL_NO_CONTEXT) {
      eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, previous);
    } else {
      upload_context_->release_current();
    }
  };
  try {
    prepared->tables = create_tables(prepared->packed, prepared->plan);
    glFinish();  // every upload done before the backend's context uses them
    upload_context_->check_errors("GL backend prepare");
  } catch (...) {
    if (prepared->tables) {
      for (GLuint b : prepared->tables->buffers()) glDeleteBuffers(1, &b);
      prepared->tables.reset();
    }
    restore();
    throw;
  }
  restore();
  return prepared;
}

void GlBackend::discard(std::vector<GLuint> buffers) const {
  std::lock_guard<std::mutex> lock(upload_mutex_);
  discarded_.insert(discarded_.end(), buffers.begin(), buffers.end());
}

void GlBackend::delete_discarded() {
  std::lock_guard<std::mutex> lock(upload_mutex_);
  for (GLuint b : discarded_) glDeleteBuffers(1, &b);
  discarded_.clear();
}

void GlBackend::adopt(std::unique_ptr<PreparedModel> prepared) {
  auto* p = dynamic_cast<Prepared*>(prepared.get());
  if (!p) throw Error(ErrorKind::Backend, "GL backend: adopt() of a version it did not prepare");
  const Model& next = p->model();
  const gl::PackedModel& packed = p->packed;
  const int32_t old_n = npoint_, n = next.npoint();
  if (n < old_n || static_cast<int32_t>(next.origin.size()) != n) {
    throw Error(ErrorKind::Backend, "GL backend: rebuild from a Model with " + std::to_string(n) + " points after " +
                                        std::to_string(old_n) + " (points are append-only)");
  }
  // The shader variants were compiled for the first version's plan; a
  // topology change adds sutures at most, which step.comp reads from the
  // spring entries, so the same programs run the next version.
  if (p->plan.element != plan_.element || p->plan.gravity != plan_.gravity || p->plan.tool != plan_.tool)
    throw Error(ErrorKind::Backend, "GL backend: a rebuild changed the step's passes beyond sutures");
  if (!p->tables) throw Error(ErrorKind::Backend, "GL backend: adopt() of a version already adopted");
  make_current();
  // The state stays on the GPU: the old points' x_t and d_t are copied as a
  // block into the new version's buffers, and each appended lane (new
  // points, padding) gets those of the old point it copies
  // (carry_state.comp), so an adopt neither waits for the tick in flight
  // nor uploads the state.
  std::vector<int32_t> from(static_cast<size_t>(packed.npad - old_n));
  for (int32_t i = old_n; i < packed.npad; ++i) {
    // Padding lanes copy the last point, as pack_model's rest state does.
    int32_t f = i < n ? next.origin[static_cast<size_t>(i)] : n - 1;
    while (f >= old_n) f = f < n ? next.origin[static_cast<size_t>(f)] : n - 1;
    from[static_cast<size_t>(i - old_n)] = f;
  }
  const GLuint x_old = x_[cur_], d_old = d_[cur_], anchors_old = anchors_;
  x_[cur_] = d_[cur_] = anchors_ = 0;  // kept from delete_model_buffers() until the copies are issued
  // The ring's copies of the last tick's end positions stay readable: the
  // reaction the next tick returns is of that tick, which ended in this state.
  for (Slot& s : slots_) s.has_positions = s.positions_adopted = false;
  delete_retired_ring();
  if (reaction_x_ && ticks_ > 0) {
    retired_ = {reaction_x_, reaction_x_map_, npad_, old_n, from};
    reaction_x_ = 0;
    reaction_x_map_ = nullptr;
    slots_[static_cast<size_t>((ticks_ - 1) % kSlots)].positions_adopted = true;
  }
  delete_model_buffers();
  plan_ = p->plan;
  model_ = &next;
  Tables tables = std::move(*p->tables);
  p->tables.reset();
  install(std::move(tables), packed, nullptr, nullptr);
  const GLsizeiptr old_bytes = static_cast<GLsizeiptr>(static_cast<size_t>(old_n) * 4 * sizeof(float));
  glCopyNamedBufferSubData(x_old, x_[0], 0, 0, old_bytes);
  glCopyNamedBufferSubData(d_old, d_[0], 0, 0, old_bytes);
  if (anchors_ && anchors_old) glCopyNamedBufferSubData(anchors_old, anchors_, 0, 0, old_bytes);
  if (!from.empty()) {
    const GLuint index = make_buffer("carried lanes' old points", from.size() * sizeof(int32_t), from.data(), 0);
    carry(x_old, d_old, index, old_n, static_cast<int32_t>(from.size()));
    ++dispatches_;
    glDeleteBuffers(1, &index);  // freed by the driver once the dispatch has run
  }
  // x_{t+1} and its increment start as x_t's, as a fresh version's do.
  const GLsizeiptr bytes = static_cast<GLsizeiptr>(packed.rest.size() * sizeof(float));
  glCopyNamedBufferSubData(x_[0], x_[1], 0, 0, bytes);
  glCopyNamedBufferSubData(d_[0], d_[1], 0, 0, bytes);
  for (GLuint b : {x_old, d_old, anchors_old})
    if (b) glDeleteBuffers(1, &b);
  context_->check_errors("GL backend rebuild");
}

GlBackend::~GlBackend() {
  make_current();
  delete_discarded();
  for (Slot& s : slots_) {
    if (s.fence) glDeleteSync(s.fence);
  }
  if (reaction_map_) glUnmapNamedBuffer(reaction_);
  if (status_map_) glUnmapNamedBuffer(status_);
  delete_retired_ring();
  delete_model_buffers();
  for (GLuint b : {reaction_, status_, layer_out_}) {
    if (b) glDeleteBuffers(1, &b);
  }
  step_ = gl::ComputeProgram();
  reduce_ = gl::ComputeProgram();
  nodal_pressure_ = gl::ComputeProgram();
  shear_smoothing_ = gl::ComputeProgram();
  carry_ = gl::ComputeProgram();
}

void GlBackend::make_current() const {
  // A renderer may have made its own context current on this thread.
  if (eglGetCurrentContext() != static_cast<EGLContext>(context_->egl_context())) context_->make_current();
}

GLuint GlBackend::create_buffer(const char* what, size_t bytes, const void* data, GLbitfield flags) {
  const GLuint buffer = make_buffer(what, bytes, data, flags);
  buffer_sizes_.emplace_back(what, bytes > 0 ? bytes : 16);
  return buffer;
}

std::string GlBackend::device() const {
  return context_->renderer() + ", " + std::to_string(threads_per_point_) + " invocation(s) per point";
}

Plan GlBackend::plan() const {
  Plan plan;
  const auto& m = *model_;
  const std::string grid = std::to_string(nchunk_) + " workgroups x " + std::to_string(ORGANSIM_GL_CHUNK) +
                           " points x " + std::to_string(threads_per_point_) + " invocation(s) per point";
  const std::string in_step = " (in step.comp's one fused dispatch per substep)";
  const std::string tets = std::to_string(m.ntet()) + " tets per vertex";
  for (Pass pass : plan_.passes) {
    std::string detail;
    switch (pass) {
      case Pass::NodalPressure:
        detail = "nodal_pressure.comp, one dispatch per substep before the step, then a storage barrier: nodal "
                 "volumes from " + tets + ", pressure per point";
        break;
      case Pass::ShearSmoothing:
        detail = "shear_smoothing.comp, one dispatch per substep before the step, then a storage barrier: smoothed "
                 "deformation gradients from " + tets + ", P(Fbar) per point";
        break;
      case Pass::Springs:
        detail = std::to_string(m.nspring()) + " springs gathered from both ends (" +
                 std::to_string(m.layout.springs.item.size()) + " slots)" +
                 (plan_.sutures > 0 ? ", " + std::to_string(plan_.sutures) + " of them sutures (tension only)" : "") +
                 in_step;
        break;
      case Pass::Volume: detail = tets + in_step; break;
      case Pass::ShearElement:
        detail = std::string(plan_.element == ElementTerm::SmoothedShear ? "smoothed " : "") + "shear element" +
                 (m.shear_damping_time > 0 ? " and its damper" : "") + " of " + tets + in_step;
        break;
      case Pass::Gravity: detail = "m g on every free point" + in_step; break;
      case Pass::SurfaceContact:
        detail = std::string(shape_name(tool_.shape)) + " against " + std::to_string(m.nsurface()) +
                 " surface triangles, each surface point recomputing its own triangles (broad phase: the " +
                 shape_name(tool_.shape) + " against each triangle's box), w_p f summed in triangle order" +
                 (hertz_layer_.id() ? ", each f lowered by the sub-cell layer's offset: before the step, "
                                      "hertz_layer_touch.comp's penalties (one invocation per triangle, " +
                                          std::to_string(layer_nblock_) +
                                          " workgroups), then hertz_layer.comp's solve over the blocks in contact "
                                          "(one workgroup), each followed by a storage barrier; only while the tool "
                                          "acts"
                                    : "") +
                 friction_plan(tool_) + in_step;
        break;
      case Pass::ToolContact:
        detail = (plan_.tool == ToolTerm::Push      ? std::string(shape_name(tool_.shape)) + " penalty contact on the points"
                  : plan_.tool == ToolTerm::Surface ? "the surface contact's force on each surface point"
                                                    : "grasp attachment springs") +
                 in_step + ", partial reaction per workgroup";
        break;
      case Pass::Integrate: detail = "position Verlet with drag, step.comp: " + grid; break;
      // The GL backend integrates by position Verlet only (make_gl_backend refuses implicit Euler).
      case Pass::Linearise:
      case Pass::ConjugateGradient:
      case Pass::VelocityUpdate: break;
    }
    plan.passes.push_back({pass_name(pass), detail});
  }
  if (plan_.sutures > 0)
    plan.per_tick.push_back({"suture-rest", std::to_string(plan_.sutures) + " sutures' rest lengths from their schedule, "
                                            "uploaded where they changed"});
  if (tool_.present) {
    plan.per_tick.push_back({"reduce-reaction", "reduce_reaction.comp while the tool acts: " + std::to_string(nchunk_) +
                                                    " workgroup partials -> 6 floats + contacts into a persistently "
                                                    "mapped ring"});
  }
  plan.per_tick.push_back({"readback", "fence per tick; the CPU reads tick n-1's reaction after submitting tick n "
                                       "(latency 1 tick, no wait unless the device is a full tick behind)"});
  for (const auto& [what, bytes] : buffer_sizes_) plan.buffers.push_back({what, bytes});
  // The step, plus one dispatch per per-point pass before it (nodal volume
  // term or smoothed shear element, never both) and the Hertz layer's two
  // while the tool acts; + 1 reduce per tick with a tool.
  plan.dispatches_per_step = 1 + (plan_.has(Pass::NodalPressure) ? 1 : 0) + (plan_.has(Pass::ShearSmoothing) ? 1 : 0) +
                             (hertz_layer_.id() ? 2 : 0);
  plan.syncs_per_step = 0;
  return plan;
}

void GlBackend::set_state(const std::vector<Vec3>& x_t, const std::vector<Vec3>& x_prev) {
  if (static_cast<int32_t>(x_t.size()) != npoint_ || static_cast<int32_t>(x_prev.size()) != npoint_) {
    throw Error(ErrorKind::Backend, "GL backend: set_state needs " + std::to_string(npoint_) + " points");
  }
  make_current();
  auto upload = [&](GLuint buffer, auto&& value_of, float w) {
    for (int32_t i = 0; i < npad_; ++i) {
      const Vec3 r = value_of(static_cast<size_t>(i < npoint_ ? i : npoint_ - 1));
      for (int k = 0; k < 3; ++k) readback_[4 * i + k] = static_cast<float>(r[k]);
      readback_[4 * i + 3] = w;
    }
    glNamedBufferSubData(buffer, 0, static_cast<GLsizeiptr>(readback_.size() * sizeof(float)), readback_.data());
  };
  upload(x_[cur_], [&](size_t i) { return x_t[i]; }, 1.0f);
  // The difference in double, then rounded: as precise as float allows.
  upload(d_[cur_], [&](size_t i) { return Vec3(x_t[i] - x_prev[i]); }, 0.0f);
  context_->check_errors("GL backend set_state");
}

void GlBackend::attach(const Attachment& attachment) {
  if (plan_.tool != ToolTerm::Pull) return;  // only a pulling tool grasps
  make_current();
  std::fill(attach_upload_.begin(), attach_upload_.end(), 0.0f);
  for (size_t k = 0; k < attachment.points.size(); ++k) {
    const int32_t p = attachment.points[k];
    if (p < 0 || p >= npoint_) {
      throw Error(ErrorKind::Backend, "GL backend: attached point " + std::to_string(p) + " out of range");
    }
    for (int j = 0; j < 3; ++j) attach_upload_[4 * p + j] = static_cast<float>(attachment.offsets[k][j]);
    attach_upload_[4 * p + 3] = 1.0f;
  }
  // An event, not per step: GL orders it after the dispatches already queued.
  glNamedBufferSubData(attach_, 0, static_cast<GLsizeiptr>(attach_upload_.size() * sizeof(float)),
                       attach_upload_.data());
}

void GlBackend::release() {
  if (plan_.tool != ToolTerm::Pull) return;
  make_current();
  std::fill(attach_upload_.begin(), attach_upload_.end(), 0.0f);
  glNamedBufferSubData(attach_, 0, static_cast<GLsizeiptr>(attach_upload_.size() * sizeof(float)),
                       attach_upload_.data());
}

void GlBackend::refresh_suture_rest() {
  // At the start of the tick, as on the CPU; only entries whose float value
  // changed are uploaded (4 bytes each, ordered before this tick's dispatches).
  for (size_t k = 0; k < suture_entries_.size(); ++k) {
    const int32_t e = suture_entries_[k];
    const float rest = static_cast<float>(model_->spring_rest_at(model_->layout.springs.item[e], time_));
    if (rest == suture_rest_[k]) continue;
    suture_rest_[k] = rest;
    glNamedBufferSubData(springs_, static_cast<GLintptr>(e * sizeof(gl::SpringEntry) + offsetof(gl::SpringEntry, rest)),
                         sizeof(float), &rest);
  }
}

Reaction GlBackend::tick(const TickRequest& request) {
  make_current();
  delete_discarded();
  const GLuint program = step_.id();
  glUseProgram(program);
  glProgramUniform1f(program, ORGANSIM_GL_U_DT, static_cast<float>(request.dt));
  glProgramUniform1f(program, ORGANSIM_GL_U_DAMPING, static_cast<float>(model_->viscous_damping * request.dt));
  glProgramUniform1f(program, ORGANSIM_GL_U_DT2, static_cast<float>(request.dt * request.dt));
  const bool tool_acts = tool_.present && request.tool_active;
  if (tool_.present) glProgramUniform1i(program, ORGANSIM_GL_U_TOOL_ACTIVE, tool_acts ? 1 : 0);
  const int slot = static_cast<int>(ticks_ % kSlots);
  Slot& current = slots_[static_cast<size_t>(slot)];
  // Its previous fence was consumed by read_slot() three ticks ago, so the CPU
  // is done with this slot; the clear is ordered before this tick's dispatches.
  glProgramUniform1i(program, ORGANSIM_GL_U_SLOT, slot);
  glClearNamedBufferSubData(status_, GL_R32UI, static_cast<GLintptr>(slot * sizeof(uint32_t)), sizeof(uint32_t),
                            GL_RED_INTEGER, GL_UNSIGNED_INT, &kNoPoint);
  refresh_suture_rest();

  for (int32_t s = 0; s < request.substeps; ++s) {
    if (tool_.present) {
      // The force of substep s acts at its start (as on the CPU): the pose there.
      const ToolPlacement placed = request.tool_at(tool_, s);
      auto set = [&](GLint location, const Vec3& v) {
        glProgramUniform3f(program, location, static_cast<float>(v.x()), static_cast<float>(v.y()),
                           static_cast<float>(v.z()));
      };
      set(ORGANSIM_GL_U_TOOL_CENTER, placed.origin);
      if (plan_.tool != ToolTerm::Pull) set(ORGANSIM_GL_U_TOOL_A, placed.a), set(ORGANSIM_GL_U_TOOL_B, placed.b);
      if (placed.jaws == 2) {
        set(ORGANSIM_GL_U_TOOL_A2, placed.a2), set(ORGANSIM_GL_U_TOOL_B2, placed.b2);
        set(ORGANSIM_GL_U_JAW_AXIS, placed.rotation * kJawAxis);
      }
      if (anchors_) {
        const Eigen::Matrix3f r = placed.rotation.toRotationMatrix().cast<float>();
        glProgramUniformMatrix3fv(program, ORGANSIM_GL_U_TOOL_ROTATION, 1, GL_FALSE, r.data());  // column-major
      }
      glProgramUniform1i(program, ORGANSIM_GL_U_REDUCE, tool_acts && s == request.substeps - 1 ? 1 : 0);
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_X_CUR, x_[cur_]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_D_CUR, d_[cur_]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_X_NEXT, x_[1 - cur_]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_D_NEXT, d_[1 - cur_]);
    if (hertz_layer_.id() && tool_acts) {
      // The layer's offset for this substep's positions, before the step reads it.
      const ToolPlacement placed = request.tool_at(tool_, s);
      glUseProgram(hertz_layer_touch_.id());
      const Eigen::Vector3f a = placed.a.cast<float>(), b = placed.b.cast<float>();
      glProgramUniform3f(hertz_layer_touch_.id(), ORGANSIM_GL_U_TOOL_A, a.x(), a.y(), a.z());
      glProgramUniform3f(hertz_layer_touch_.id(), ORGANSIM_GL_U_TOOL_B, b.x(), b.y(), b.z());
      glDispatchCompute(static_cast<GLuint>(layer_nblock_), 1, 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      glUseProgram(hertz_layer_.id());
      glDispatchCompute(1, 1, 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      glUseProgram(program);
      dispatches_ += 2;
    }
    // Every nodal pressure or smoothed stress before any force that reads it.
    for (const gl::ComputeProgram* pass : {&nodal_pressure_, &shear_smoothing_}) {
      if (!pass->id()) continue;
      glUseProgram(pass->id());
      glDispatchCompute(static_cast<GLuint>(nchunk_), 1, 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      glUseProgram(program);
      ++dispatches_;
    }
    glDispatchCompute(static_cast<GLuint>(nchunk_), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    ++dispatches_;
    cur_ = 1 - cur_;  // x_{t+1} becomes x_t
    time_ += request.dt;
  }

  current.has_reaction = tool_acts;
  current.t_end = time_;
  if (tool_acts) {
    glUseProgram(reduce_.id());
    glProgramUniform1i(reduce_.id(), ORGANSIM_GL_U_SLOT, slot);
    glDispatchCompute(1, 1, 1);
    ++dispatches_;
  }
  // Make this tick's reaction and status writes visible to the CPU through
  // the mappings, and to the status clear that reuses the slot later.
  glMemoryBarrier(GL_CLIENT_MAPPED_BUFFER_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  current.has_positions = reaction_x_ != 0;
  current.positions_adopted = false;
  if (current.has_positions) {
    const GLsizeiptr xbytes = static_cast<GLsizeiptr>(static_cast<size_t>(npad_) * 4 * sizeof(float));
    glCopyNamedBufferSubData(x_[cur_], reaction_x_, 0, slot * xbytes, xbytes);
  }
  if (current.fence) glDeleteSync(current.fence);
  current.fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  glFlush();  // start the work now; the fence is polled next tick

  Reaction reaction;  // zero until the first tick has completed
  if (ticks_ > 0) reaction = read_slot(static_cast<int>((ticks_ - 1) % kSlots));
  ++ticks_;
  if (options_.debug) context_->check_errors("GL backend tick");
  return reaction;
}

Reaction GlBackend::read_slot(int slot) {
  Slot& s = slots_[static_cast<size_t>(slot)];
  Reaction reaction;
  if (!s.fence) return reaction;
  // Normally already signalled: the device finished tick n-1 while the CPU
  // prepared tick n. Waiting only happens when it is a whole tick behind.
  GLenum status = glClientWaitSync(s.fence, 0, 0);
  if (status == GL_TIMEOUT_EXPIRED) {
    ++blocked_readbacks_;
    status = glClientWaitSync(s.fence, GL_SYNC_FLUSH_COMMANDS_BIT, kReadbackTimeoutNs);
  }
  if (status == GL_WAIT_FAILED || status == GL_TIMEOUT_EXPIRED) {
    throw Error(ErrorKind::Backend, std::string("GL backend: glClientWaitSync on the reaction fence ") +
                                        (status == GL_WAIT_FAILED ? "failed" : "timed out after 10 s"));
  }
  glDeleteSync(s.fence);
  s.fence = nullptr;
  reaction_slot_ = slot;
  const uint32_t bad = status_map_[slot];
  if (bad != kNoPoint) {
    const int32_t p = static_cast<int32_t>(bad);
    const double t0 = s.t_end;
    throw Error(ErrorKind::Numerical,
                "GL backend: non-finite position of point " + std::to_string(model_->input_of_internal[p]) +
                    " (input numbering) in the tick ending at t = " + std::to_string(t0) +
                    " s: the simulation blew up (dt above the critical step, a sliver tet or an extreme tool "
                    "stiffness); positions are no longer valid");
  }
  if (!s.has_reaction) return reaction;
  const float* r = reaction_map_ + 8 * slot;
  reaction.force = Vec3(r[0], r[1], r[2]);
  reaction.contacts = static_cast<int32_t>(r[3] + 0.5f);
  reaction.torque = Vec3(r[4], r[5], r[6]);
  reaction.grip = r[7];
  return reaction;
}

void GlBackend::positions(std::vector<Vec3>& out) const {
  make_current();
  ++state_readbacks_;
  glGetNamedBufferSubData(x_[cur_], 0, static_cast<GLsizeiptr>(static_cast<size_t>(npoint_) * 4 * sizeof(float)),
                          readback_.data());
  out.resize(static_cast<size_t>(npoint_));
  for (int32_t i = 0; i < npoint_; ++i) out[i] = Vec3(readback_[4 * i], readback_[4 * i + 1], readback_[4 * i + 2]);
  context_->check_errors("GL backend positions");
}

void GlBackend::reaction_positions(std::vector<Vec3>& out) const {
  if (!options_.keep_reaction_positions) {
    throw Error(ErrorKind::Backend, "GL backend: reaction_positions() needs GlBackendOptions::keep_reaction_positions");
  }
  const Slot* s = reaction_slot_ >= 0 ? &slots_[static_cast<size_t>(reaction_slot_)] : nullptr;
  if (!s || !(s->has_positions || s->positions_adopted))
    throw Error(ErrorKind::Backend, "GL backend: reaction_positions() before the first tick's end");
  out.resize(static_cast<size_t>(npoint_));
  const auto from = [&](const float* x, int32_t i, int32_t k) { out[i] = Vec3(x[4 * k], x[4 * k + 1], x[4 * k + 2]); };
  if (s->has_positions) {
    const float* x = reaction_x_map_ + static_cast<size_t>(reaction_slot_) * npad_ * 4;
    for (int32_t i = 0; i < npoint_; ++i) from(x, i, i);
    return;
  }
  // The tick before an adopt(): the old version's ring, its appended points
  // as the adopt carried them over.
  const float* x = retired_.map + static_cast<size_t>(reaction_slot_) * retired_.npad * 4;
  for (int32_t i = 0; i < npoint_; ++i)
    from(x, i, i < retired_.npoint ? i : retired_.appended_from[static_cast<size_t>(i - retired_.npoint)]);
}

void GlBackend::carry(GLuint x_old, GLuint d_old, GLuint index, int32_t first, int32_t count) {
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_X_CUR, x_old);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_D_CUR, d_old);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_X_NEXT, x_[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_D_NEXT, d_[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, ORGANSIM_GL_B_CARRY, index);
  glUseProgram(carry_.id());
  glProgramUniform1i(carry_.id(), ORGANSIM_GL_U_CARRY_FIRST, first);
  glProgramUniform1i(carry_.id(), ORGANSIM_GL_U_CARRY_COUNT, count);
  glDispatchCompute(static_cast<GLuint>(std::max(1, (count + ORGANSIM_GL_CHUNK - 1) / ORGANSIM_GL_CHUNK)), 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

void GlBackend::delete_retired_ring() {
  if (retired_.map) glUnmapNamedBuffer(retired_.buffer);
  if (retired_.buffer) glDeleteBuffers(1, &retired_.buffer);
  retired_ = {};
}

void GlBackend::forces(std::vector<Vec3>& out) const {
  if (!force_) throw Error(ErrorKind::Backend, "GL backend: forces() needs GlBackendOptions::record_forces");
  make_current();
  ++state_readbacks_;
  glGetNamedBufferSubData(force_, 0, static_cast<GLsizeiptr>(static_cast<size_t>(npoint_) * 4 * sizeof(float)),
                          readback_.data());
  out.resize(static_cast<size_t>(npoint_));
  for (int32_t i = 0; i < npoint_; ++i) out[i] = Vec3(readback_[4 * i], readback_[4 * i + 1], readback_[4 * i + 2]);
}

std::unique_ptr<Backend> make_gl_backend(const Model& model, const BackendTool& tool,
                                         const GlBackendOptions& options) {
  return std::make_unique<GlBackend>(model, tool, options);
}

}  // namespace organsim
