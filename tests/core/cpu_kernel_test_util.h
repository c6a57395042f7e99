#pragma once
// Models and scenes shared by the simd kernel tests (float and double):
// a jittered box with a fixed base, and 1000-step runs of every scene
// variant (lean, volume + gravity, push, pull), with each per-tet term the
// kernels run: the per-tet or the averaged nodal volume term, or the shear
// element (smoothed, or per tet) at a Poisson ratio below 1/4.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/reference_backend.h"
#include "core/run/run.h"
#include "tests/core/test_models.h"

namespace organsim::testing {

constexpr double kSize = 0.05;  // m, edge of the test box

// The simd kernel's targets a test runs on, each its own test case: every
// target compiled in that this CPU runs (the portable fallback included).
inline std::vector<std::string> fast_kernels() {
  std::vector<std::string> out;
  for (const SimdTarget& t : simd_targets_supported()) out.push_back(t.name);
  return out;
}
inline CpuBackendOptions fast_kernel(const std::string& kernel, Precision precision, int threads = 1) {
  return {precision, threads, kernel};
}

// What a test steps: the CPU backend with its options, or (without) the
// reference backend's Verlet (reference_backend.h), the judge of the kernel.
struct Stepper {
  std::optional<CpuBackendOptions> cpu;
  Stepper() = default;
  Stepper(const CpuBackendOptions& options) : cpu(options) {}  // NOLINT: implicit, so options read as a stepper
  std::unique_ptr<Backend> make(const Model& model, const BackendTool& tool = {}) const {
    return cpu ? make_cpu_backend(model, tool, *cpu) : make_reference_backend(model, tool, Integrator::Verlet);
  }
  // What device() says of its kernel.
  std::string label() const { return cpu ? "simd (" + cpu->simd + ") kernel" : "Verlet (reference, double)"; }
};
inline const Stepper kReference;
// gtest's name for a kernel's test case.
inline std::string kernel_test_name(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

// Which per-tet term a test model has: none, a volume term per tet
// (volume_modulus 30 kPa) or averaged nodal (poisson_ratio 0.45, where the
// volume term is most of the stiffness), or the shear element with its
// damper, smoothed (the default formulation) at poisson_ratio 0, 0.1 and
// 0.2, or per tet at 0.2.
enum class VolumeTerm { None, PerTet, Nodal, Shear0, Shear01, Shear02, ShearPerTet };

// The terms every kernel test runs through.
inline constexpr VolumeTerm kEveryTerm[] = {VolumeTerm::PerTet,  VolumeTerm::Nodal,   VolumeTerm::Shear0,
                                            VolumeTerm::Shear01, VolumeTerm::Shear02, VolumeTerm::ShearPerTet};

inline const char* volume_term_name(VolumeTerm v) {
  switch (v) {
    case VolumeTerm::None: return "no volume term";
    case VolumeTerm::PerTet: return "per-tet volume term";
    case VolumeTerm::Nodal: return "nodal volume term";
    case VolumeTerm::Shear0: return "smoothed shear element, nu 0";
    case VolumeTerm::Shear01: return "smoothed shear element, nu 0.1";
    case VolumeTerm::Shear02: return "smoothed shear element, nu 0.2";
    case VolumeTerm::ShearPerTet: return "per-tet shear element, nu 0.2";
  }
  return "";
}

// A box of cells^3 cubes cut into tets, interior points moved by up to
// `jitter` of a cell, its base (z = 0) fixed.
inline Model random_model(unsigned seed, int cells, VolumeTerm volume, bool gravity,
                          int32_t chunk = kDefaultChunkSize, double jitter = 0.25) {
  Material material;
  material.density = 1000;
  material.young_modulus = 4000;
  material.spring_damping_time = 0.01;
  material.viscous_damping = 2;
  if (volume == VolumeTerm::PerTet) material.volume_modulus = 30000;
  if (volume == VolumeTerm::Nodal) material.poisson_ratio = 0.45;
  if (volume == VolumeTerm::Shear0) material.poisson_ratio = 0;
  if (volume == VolumeTerm::Shear01) material.poisson_ratio = 0.1;
  if (volume == VolumeTerm::Shear02 || volume == VolumeTerm::ShearPerTet) material.poisson_ratio = 0.2;
  if (volume == VolumeTerm::ShearPerTet) material.shear_formulation = ShearFormulation::PerTet;
  ModelOptions options;
  options.gravity = gravity ? Vec3(0.3, -1.0, -9.81) : Vec3::Zero();
  options.chunk_size = chunk;
  FixedSelector base;  // hold the base so the tool has something to push against
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-9);
  base.normal = Vec3(0, 0, -1);
  options.fixed.push_back(base);
  return build_model(jittered_box(cells, kSize, jitter, seed), material, options);
}

// A deformed, moving state (displacements of ~0.5 mm, increments of ~5e-6 m
// per step of dt) that float holds exactly (u and d are floats there).
inline void moving_state(const Model& model, unsigned seed, double dt, std::vector<Vec3>& x, std::vector<Vec3>& x_prev) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 1);
  x.resize(model.npoint());
  x_prev.resize(model.npoint());
  for (int32_t i = 0; i < model.npoint(); ++i) {
    const Vec3 u = (5e-4 * Vec3(noise(rng), noise(rng), noise(rng))).cast<float>().cast<double>();
    const Vec3 d = (dt * 0.05 * Vec3(noise(rng), noise(rng), noise(rng))).cast<float>().cast<double>();
    x[i] = model.rest_position[i] + u;
    x_prev[i] = x[i] - d;
  }
}

// Positions after one step of dt from (x, x_prev).
inline std::vector<Vec3> one_step(const Model& model, const Stepper& stepper, const std::vector<Vec3>& x,
                                  const std::vector<Vec3>& x_prev, double dt) {
  auto backend = stepper.make(model);
  backend->set_state(x, x_prev);
  run_ticks(*backend, 1, dt, 1);
  std::vector<Vec3> after;
  backend->positions(after);
  return after;
}

// One step of dt = 1e-4 s from a deformed, moving state (moving_state) on
// the reference (reference_backend.h's Verlet) and on `options`, for each
// term, seeds 1-3 and boxes of 3, 6 and 12 cells (12 cells, about
// 10k tets, open more tet batches at once than the packing keeps open, so
// its closing path runs too): calls check(model, x, x_prev, dt, ref, got)
// with the positions after the step.
template <class Check>
inline void for_each_one_step_against_the_reference(const CpuBackendOptions& options, Check check) {
  const double dt = 1e-4;
  for (VolumeTerm volume : kEveryTerm) {
    for (unsigned seed : {1u, 2u, 3u}) {
      for (int cells : {3, 6, 12}) {
        SCOPED_TRACE(std::string(volume_term_name(volume)) + ", seed " + std::to_string(seed) + ", " +
                     std::to_string(cells) + " cells");
        const Model model = random_model(seed, cells, volume, true);
        std::vector<Vec3> x, x_prev;
        moving_state(model, seed, dt, x, x_prev);
        const auto ref = one_step(model, kReference, x, x_prev, dt);
        const auto got = one_step(model, options, x, x_prev, dt);
        check(model, x, x_prev, dt, ref, got);
      }
    }
  }
}

// Push: the sphere against the surface triangles (the default contact);
// PushPoints: the same motion with the penalty on the points. Capsule and
// CapsulePoints: a capsule (radius 8 mm, a 3 cm shaft rising from its tip,
// the tool's origin) pressed in while it turns a quarter turn about z.
enum class Scene { Lean, Full, Push, PushPoints, Capsule, CapsulePoints, Pull };

// 1000 steps (50 ticks of 20) of a scene; returns the positions and the last reaction.
inline std::vector<Vec3> run_scene(const Model& model, Scene scene, const Stepper& stepper, Reaction& last,
                                   int ticks = 50) {
  BackendTool tool;
  if (scene == Scene::Push) tool = {true, ToolMode::Push, 0.02, 500, ToolContact::Surface};
  if (scene == Scene::PushPoints) tool = {true, ToolMode::Push, 0.02, 500, ToolContact::Points};
  const bool capsule = scene == Scene::Capsule || scene == Scene::CapsulePoints;
  if (capsule) {
    tool = {true, ToolMode::Push, 0.008, 500, scene == Scene::Capsule ? ToolContact::Surface : ToolContact::Points};
    tool.shape = ToolShape::Capsule;
    tool.end_b = Vec3(0.03, 0, 0.012);
  }
  if (scene == Scene::Pull) tool = {true, ToolMode::Pull, 0.01, 200};
  auto backend = stepper.make(model, tool);
  const Vec3 top(0.025, 0.025, kSize);
  if (scene == Scene::Lean) {
    // No load at all: start stretched 5 % upwards and let it ring.
    std::vector<Vec3> x = model.rest_position;
    for (int32_t i = 0; i < model.npoint(); ++i)
      if (!model.fixed[i]) x[i].z() *= 1.05;
    backend->set_state(x, x);
  }
  if (scene == Scene::Pull) {
    std::vector<Vec3> x;
    backend->positions(x);
    backend->attach(select_grasp(model, x, top, 0.012));
  }
  TickRequest request;
  request.dt = 5e-5;
  request.substeps = 20;
  request.tool_active = tool.present;
  for (int i = 0; i < ticks; ++i) {
    // Push: the sphere's centre comes down to 1.5 cm inside the box; pull: the top is lifted 5 mm.
    const double s0 = i / 50.0, s1 = (i + 1) / 50.0;
    const bool push = scene == Scene::Push || scene == Scene::PushPoints;
    Vec3 from = push ? Vec3(top + Vec3(0, 0, 0.02 - 0.035 * s0)) : Vec3(top + Vec3(0, 0, 0.005 * s0));
    Vec3 to = push ? Vec3(top + Vec3(0, 0, 0.02 - 0.035 * s1)) : Vec3(top + Vec3(0, 0, 0.005 * s1));
    if (capsule) {
      // The tip comes down to 6 mm inside the box.
      from = top + Vec3(0, 0, 0.012 - 0.026 * s0), to = top + Vec3(0, 0, 0.012 - 0.026 * s1);
      request.turn_from = Quat(Eigen::AngleAxisd(1.5708 * s0, Vec3::UnitZ()));
      request.turn_to = Quat(Eigen::AngleAxisd(1.5708 * s1, Vec3::UnitZ()));
    }
    request.tool_from = from;
    request.tool_to = to;
    last = backend->tick(request);
  }
  std::vector<Vec3> x;
  backend->positions(x);
  return x;
}

inline const char* scene_name(Scene s) {
  switch (s) {
    case Scene::Lean: return "lean (springs only)";
    case Scene::Full: return "volume + gravity";
    case Scene::Push: return "push (surface contact)";
    case Scene::PushPoints: return "push (point contact)";
    case Scene::Capsule: return "turning capsule (surface contact)";
    case Scene::CapsulePoints: return "turning capsule (point contact)";
    case Scene::Pull: return "pull";
  }
  return "";
}

// Every scene variant on `options` against the reference, 1000 steps each, with `volume` in all but the lean scene
// (springs only, so run only with the per-tet term): the scene must deform
// the model; positions must agree within `position_tol` m and, with a
// tool, the contacts exactly and the reaction force within `reaction_tol`
// of its size.
inline void expect_scenes_track_the_reference(const CpuBackendOptions& options, double position_tol,
                                              double reaction_tol, VolumeTerm volume = VolumeTerm::PerTet) {
  for (Scene scene :
       {Scene::Lean, Scene::Full, Scene::Push, Scene::PushPoints, Scene::Capsule, Scene::CapsulePoints, Scene::Pull}) {
    const bool lean = scene == Scene::Lean;
    if (lean && volume != VolumeTerm::PerTet) continue;
    SCOPED_TRACE(volume_term_name(volume));
    const Model model = random_model(7, 5, lean ? VolumeTerm::None : volume, !lean);
    Reaction rd, rf;
    const auto xd = run_scene(model, scene, kReference, rd);
    const auto xf = run_scene(model, scene, options, rf);
    double worst = 0, moved = 0;
    for (size_t i = 0; i < xd.size(); ++i) {
      worst = std::max(worst, (xd[i] - xf[i]).norm());
      moved = std::max(moved, (xd[i] - model.rest_position[i]).norm());
    }
    ASSERT_GT(moved, 1e-4) << scene_name(scene) << ": the scene must deform the model to test anything";
    EXPECT_LT(worst, position_tol) << scene_name(scene);
    if (scene != Scene::Lean && scene != Scene::Full) {
      ASSERT_GT(rd.contacts, 0) << scene_name(scene);
      EXPECT_EQ(rd.contacts, rf.contacts) << scene_name(scene);
      EXPECT_LT((rd.force - rf.force).norm(), reaction_tol * rd.force.norm()) << scene_name(scene);
    }
  }
}

// A fast kernel on two threads against one, bitwise, in the scenes with
// volume, push and pull, for each term. 200 steps: enough for contact and
// motion (a loaded machine makes every two-thread step slow, and bitwise
// equality needs no more).
inline void expect_two_threads_bit_identical_to_one(const CpuBackendOptions& options) {
  CpuBackendOptions two = options;
  two.threads = 2;
  for (VolumeTerm volume : kEveryTerm) {
    const Model model = random_model(3, 6, volume, true);
    for (Scene scene : {Scene::Full, Scene::Push, Scene::PushPoints, Scene::Capsule, Scene::Pull}) {
      SCOPED_TRACE(volume_term_name(volume));
      Reaction r1, r2;
      const auto x1 = run_scene(model, scene, options, r1, 10);
      const auto x2 = run_scene(model, scene, two, r2, 10);
      EXPECT_EQ(r1.force, r2.force) << scene_name(scene);  // bitwise: per-chunk partials summed in order
      EXPECT_EQ(r1.torque, r2.torque) << scene_name(scene);
      for (size_t i = 0; i < x1.size(); ++i) ASSERT_EQ(x1[i], x2[i]) << scene_name(scene) << ", point " << i;
    }
  }
}

// A fast kernel from rest without gravity, 100 steps,
// for each term and, with the nodal term and the smoothed shear element,
// after a cut (a rebuild): rest lengths, tet volumes and nodal volumes come
// from the kernel's own arithmetic on the rounded rest positions, and the
// shear element reads displacements (F = I exactly), so there is no force
// at rest and nothing may move at all.
inline void expect_rest_state_stays_put(const CpuBackendOptions& options) {
  for (VolumeTerm volume : kEveryTerm) {
    const Model model = random_model(5, 4, volume, false);
    auto backend = make_cpu_backend(model, {}, options);
    run_ticks(*backend, 10, 1e-4, 10);
    std::vector<Vec3> x;
    backend->positions(x);
    for (int32_t i = 0; i < model.npoint(); ++i)
      ASSERT_EQ(x[i], model.rest_position[i]) << volume_term_name(volume) << ", point " << i;
  }
  for (VolumeTerm volume : {VolumeTerm::Nodal, VolumeTerm::Shear01}) {
    // No jitter, so that x = 0.025 (between cells 1 and 2) is a plane of tet faces.
    const Model model = random_model(5, 4, volume, false, kDefaultChunkSize, 0);
    const Model cut = rebuild_model(model, split_across_plane_x(model, 0.025));
    ASSERT_GT(cut.npoint(), model.npoint());
    auto backend = make_cpu_backend(model, {}, options);
    backend->rebuild(cut);
    run_ticks(*backend, 10, 1e-4, 10);
    std::vector<Vec3> x;
    backend->positions(x);
    for (int32_t i = 0; i < cut.npoint(); ++i)
      ASSERT_EQ(x[i], cut.rest_position[i]) << volume_term_name(volume) << ", after a cut, point " << i;
  }
}

// A push into the top of a box (no jitter) that is cut through at
// x = 0.025 after 10 ticks, then pushed 20 ticks more (600 steps), with
// each term, on the reference and on
// `options`: the cut's sides must part in the reference, and positions
// must agree within `position_tol` m.
inline void expect_cut_run_tracks_the_reference(const CpuBackendOptions& options, double position_tol) {
  for (VolumeTerm volume : kEveryTerm) {
    SCOPED_TRACE(volume_term_name(volume));
    // No jitter, so that x = 0.025 (between cells 1 and 2) is a plane of tet faces.
    const Model model = random_model(4, 4, volume, true, kDefaultChunkSize, 0);
    const Model cut = rebuild_model(model, split_across_plane_x(model, 0.025));
    ASSERT_GT(cut.npoint(), model.npoint());
    BackendTool tool{true, ToolMode::Push, 0.02, 500};
    std::vector<Vec3> x[2];
    const Stepper run_options[2] = {kReference, options};
    for (int k = 0; k < 2; ++k) {
      TickRequest request;
      request.dt = 5e-5;
      request.substeps = 20;
      request.tool_active = true;
      request.tool_from = request.tool_to = Vec3(0.025, 0.025, kSize + 0.01);
      auto backend = run_options[k].make(model, tool);
      for (int i = 0; i < 10; ++i) backend->tick(request);
      backend->rebuild(cut);
      EXPECT_NE(backend->device().find(run_options[k].label()), std::string::npos)
          << backend->device();
      // The tool pushes into the cut's top edge, so the sides part.
      request.tool_to = Vec3(0.025, 0.025, kSize - 0.01);
      for (int i = 0; i < 20; ++i) backend->tick(request);
      backend->positions(x[k]);
    }
    ASSERT_EQ(x[0].size(), static_cast<size_t>(cut.npoint()));
    ASSERT_EQ(x[1].size(), x[0].size());
    double worst = 0, apart = 0;
    for (int32_t p = model.npoint(); p < cut.npoint(); ++p)
      apart = std::max(apart, (x[0][p] - x[0][cut.origin[p]]).norm());
    for (size_t i = 0; i < x[0].size(); ++i) worst = std::max(worst, (x[0][i] - x[1][i]).norm());
    EXPECT_GT(apart, 1e-6) << "the cut's two sides must move apart for the test to mean anything";
    EXPECT_LT(worst, position_tol);
  }
}

}  // namespace organsim::testing
