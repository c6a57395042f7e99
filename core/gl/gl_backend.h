#pragma once
// The GL backend: the whole Verlet step as one fused GLSL compute dispatch per
// substep over the Model's SELL-C gather layout (C = workgroup size), float
// state in storage buffers (x_t and x_t - x_{t-1}, ping-pong), and the tool reaction reduced on the GPU and read
// back one tick late through a fence and a persistently mapped buffer, so the
// step never waits for the GPU. A non-finite position is flagged on the GPU
// and read back the same way: tick() then throws Error(Numerical). See docs/gl.md.
#include <array>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "core/gl/egl_context.h"
#include "core/gl/gl_api.h"
#include "core/gl/gl_model_pack.h"
#include "core/gl/gl_program.h"
#include "core/sim/backend.h"

namespace organsim {

struct GlBackendOptions {
  bool debug = gl::EglContextOptions::default_debug();  // GL_KHR_debug errors become Errors
  // Tests: also store every point's total force of the last substep (forces()).
  bool record_forces = false;
  // Invocations that share one point's gathers in step.comp (1..16); 0: 1 on
  // a software renderer (llvmpipe runs each invocation on the CPU, where more
  // of them only add barriers) and 8 on a hardware GPU (docs/gl.md).
  int32_t threads_per_point = 0;
  // Copy every tick's end positions into a mapped ring on the GPU, for
  // reaction_positions() (organsim serve's reply stiffness and surface)
  // without a read-back that waits for the tick in flight. Off:
  // reaction_positions() throws.
  bool keep_reaction_positions = false;
};

// Creates its own headless context (gl::EglContext); throws Error(Backend)
// when none can be made or a shader fails. Never falls back to the CPU.
std::unique_ptr<Backend> make_gl_backend(const Model& model, const BackendTool& tool,
                                         const GlBackendOptions& options = {});

class GlBackend final : public Backend {
 public:
  GlBackend(const Model& model, const BackendTool& tool, const GlBackendOptions& options);
  ~GlBackend() override;

  std::string name() const override { return "gl"; }
  std::string device() const override;
  std::string precision() const override { return "float"; }
  Plan plan() const override;
  const StepPlan& step_plan() const override { return plan_; }
  int32_t reaction_latency_ticks() const override { return 1; }
  // Non-finite positions are flagged on the GPU every tick (status ring).
  int32_t default_check_interval_ticks() const override { return 50; }
  Reaction tick(const TickRequest& request) override;
  void attach(const Attachment& attachment) override;
  void release() override;
  // prepare: gl::pack_model and the tables uploaded on a context of its own
  // that shares this one's objects (safe on another thread while this
  // backend ticks; the caller's current context is restored); adopt: the
  // state read back and uploaded, the tables swapped in.
  std::unique_ptr<PreparedModel> prepare(const Model& next) const override;
  void adopt(std::unique_ptr<PreparedModel> prepared) override;
  void positions(std::vector<Vec3>& out) const override;
  void reaction_positions(std::vector<Vec3>& out) const override;
  double time() const override { return time_; }

  // For a renderer drawing straight from the simulation (same or shared
  // context): the storage buffer holding x_t as vec4 (w = 1), internal
  // numbering, first point_count() entries valid. The id changes every
  // substep (ping-pong), so ask again after each tick.
  GLuint position_buffer() const { return x_[cur_]; }
  int32_t point_count() const { return npoint_; }
  const gl::EglContext& context() const { return *context_; }

  // x_{t-1} is kept as d = x_t - x_{t-1}, computed here in double.
  void set_state(const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev) override;
  // Total force on each point during the last substep, N (record_forces only).
  void forces(std::vector<Vec3>& out) const;

  // Counters: compute dispatches issued, ticks whose reaction was not ready
  // when read (the CPU then waited for it; 0 means the readback never stalled).
  int64_t dispatches() const { return dispatches_; }
  int64_t blocked_readbacks() const { return blocked_readbacks_; }
  // Reads of the state back to the CPU (positions(), forces()); an adopt()
  // carries the state over on the GPU and adds none.
  int64_t state_readbacks() const { return state_readbacks_; }
  int32_t threads_per_point() const { return threads_per_point_; }

 private:
  void make_current() const;
  GLuint create_buffer(const char* what, size_t bytes, const void* data, GLbitfield flags);
  Reaction read_slot(int slot);
  // The model's tables (everything but the state), on whichever context is
  // current: the backend's, or prepare()'s upload context.
  struct Tables {
    GLuint mass = 0, chunks = 0, springs = 0, tets = 0, rest = 0, shear_params = 0, nodal_params = 0, pressure = 0,
           shear_stress = 0, surface_range = 0, surface_tris = 0, partials = 0, force = 0, layer_tris = 0,
           layer_touch = 0, layer_blocks = 0;
    int32_t layer_ntri = 0;  // triangles in layer_tris
    std::vector<std::pair<const char*, size_t>> sizes;  // for plan().buffers
    std::vector<GLuint> buffers() const;                // the non-zero ids
  };
  struct Prepared;
  Tables create_tables(const gl::PackedModel& packed, const StepPlan& plan) const;
  // Makes `tables` the model's and creates the state buffers (x_t, d_t
  // given, npad x 4; null: left for adopt() to fill on the GPU) and the
  // attachment, friction-anchor (none anchored) and end-position buffers;
  // binds them all.
  void install(Tables tables, const gl::PackedModel& packed, const float* x, const float* d);
  // Buffers of a Prepared dropped without adopt(), deleted on the backend's
  // context at its next tick (or at its end).
  void discard(std::vector<GLuint> buffers) const;
  void delete_discarded();
  void delete_model_buffers();
  // Writes the sutures' rest lengths at time_ into their spring entries.
  void refresh_suture_rest();

  const Model* model_;  // the current version (adopt() moves it on)
  BackendTool tool_;
  GlBackendOptions options_;
  std::unique_ptr<gl::EglContext> context_;
  // prepare()'s context, sharing objects with context_ (made by the first prepare()).
  mutable std::unique_ptr<gl::EglContext> upload_context_;
  mutable std::mutex upload_mutex_;  // upload_context_ and discarded_
  mutable std::vector<GLuint> discarded_;
  int32_t npoint_ = 0, npad_ = 0, nchunk_ = 0, layer_nblock_ = 0;
  StepPlan plan_;  // the passes of the current version's step (the shader variants follow it)
  int32_t threads_per_point_ = 1;

  // nodal_pressure_ with the nodal volume term only, shear_smoothing_ with the
  // smoothed shear element only (id 0 otherwise).
  gl::ComputeProgram step_, reduce_, nodal_pressure_, shear_smoothing_, carry_, hertz_layer_touch_, hertz_layer_;
  // Ping-pong pairs: x_[cur_], d_[cur_] hold x_t and d_t = x_t - x_{t-1};
  // the step writes x_[1 - cur_], d_[1 - cur_].
  std::array<GLuint, 2> x_{}, d_{};
  int cur_ = 0;
  GLuint mass_ = 0, chunks_ = 0, springs_ = 0, tets_ = 0, nodal_params_ = 0, pressure_ = 0, rest_ = 0, shear_params_ = 0,
         shear_stress_ = 0, attach_ = 0, surface_range_ = 0, surface_tris_ = 0, anchors_ = 0, partials_ = 0, reaction_ = 0, force_ = 0, status_ = 0,
         layer_tris_ = 0, layer_touch_ = 0, layer_blocks_ = 0, layer_out_ = 0;
  const float* reaction_map_ = nullptr;   // persistently mapped ring (READBACK_SLOTS x 8 floats)
  const uint32_t* status_map_ = nullptr;  // persistently mapped ring (READBACK_SLOTS uints)
  // keep_reaction_positions: x at the end of each tick, persistently
  // mapped (READBACK_SLOTS x npad x 4 floats); made with the model's buffers.
  GLuint reaction_x_ = 0;
  const float* reaction_x_map_ = nullptr;
  std::vector<std::pair<const char*, size_t>> buffer_sizes_;
  size_t ring_buffers_ = 0;  // entries of buffer_sizes_ that outlive a rebuild

  // Readback ring: the fence and whether the slot holds a reaction.
  struct Slot {
    GLsync fence = nullptr;
    bool has_reaction = false;
    double t_end = 0;  // simulated time at the end of that tick, s
    bool has_positions = false;      // its end positions are in reaction_x_ (keep_reaction_positions)
    bool positions_adopted = false;  // they are in retired_ (the tick before an adopt())
  };
  std::vector<Slot> slots_;
  int reaction_slot_ = -1;  // the slot whose reaction tick() last returned
  // The end-positions ring of the version before the last adopt(), kept
  // mapped: the tick before the adopt ended in it, and the reaction the
  // next tick returns is of that tick. Its points, then the appended ones
  // (each the old point it copies, as the GPU carried them over).
  struct RetiredRing {
    GLuint buffer = 0;
    const float* map = nullptr;
    int32_t npad = 0, npoint = 0;
    std::vector<int32_t> appended_from;
  } retired_;
  void delete_retired_ring();
  // carry_state.comp: lanes [first, first + count) of x_[0] and d_[0] from
  // the old points `index` names in x_old and d_old.
  void carry(GLuint x_old, GLuint d_old, GLuint index, int32_t first, int32_t count);
  int64_t ticks_ = 0;
  double time_ = 0;
  int64_t dispatches_ = 0, blocked_readbacks_ = 0;
  mutable int64_t state_readbacks_ = 0;
  std::vector<float> attach_upload_;  // sized once (npad x 4)
  std::vector<int32_t> suture_entries_;  // spring entries of sutures (2 per suture)
  std::vector<float> suture_rest_;       // the rest length last uploaded to each
  mutable std::vector<float> readback_;  // positions() scratch (npad x 4)
};

}  // namespace organsim
