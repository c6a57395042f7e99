#pragma once
// The reference: every integrator on the CPU in double precision on one
// thread, on the reference forces (core/sim/reference_forces.h, a plain
// scatter of the force law) and the surface contact pass the CPU backend
// runs (core/sim/surface_contact.h, which keeps friction's anchors). Every
// other path is tested against it: the simd kernel in both precisions and
// on every target, the GL backend, the scatter step.
//
// Verlet: the CPU backend's position Verlet with drag, on positions x and
// the step's increment d = x_t - x_{t-1} (velocity d / dt for the
// dampers): d' = d + dt^2 f(x, d / dt) / m with the drag -alpha m d / dt in
// f, x' = x + d'; fixed points stay put.
//
// Implicit Euler: each step evaluates the force law at the step's start,
// linearises it (core/sim/implicit_system.h) and solves
//   (M + h D + h^2 K) dv = h (f - h K v)
// by preconditioned conjugate gradients, warm-started from the last step's
// dv, with the fixed points projected out; then v += dv, x += h v. With
// newton_iterations > 1 the nonlinear residual M (v1 - v0) - h f(x0 + h v1,
// v1) is driven further by Newton steps on the same system at the new
// state, each with a backtracking line search. The step is unconditionally
// stable for the linear part, so time.dt is not bounded by dt_crit; it
// damps numerically (docs/integrators.md). The tool's contact and a pulling
// tool's attachments are springs in the system (their stiffness inside it,
// so a stiff contact is stable too). The implicit solve (linearisation,
// products, preconditioner) shares out over `threads`; the force pass
// runs on one. Results do not depend on the thread count.
#include <memory>
#include <optional>
#include <string>

#include "core/sim/backend.h"
#include "core/sim/cpu_kernel_simd.h"

namespace organsim {

enum class Preconditioner : uint8_t {
  BlockJacobi,   // the inverse of each point's 3x3 diagonal block, at every linearisation
  TwoLevel,      // block Jacobi plus a coarse correction on aggregates' rigid modes (core/sim/coarse_space.h)
  RestCholesky,  // a sparse Cholesky factor of the rest system M + h D_rest + h^2 K_rest, refreshed when h or the Model changes
};
// "block_jacobi", "two_level", "rest_cholesky".
const char* preconditioner_name(Preconditioner preconditioner);

// The solver's settings (scenario `time`); which implicit integrator is
// make_reference_backend's argument, as time.integrator is the scenario's.
struct ImplicitOptions {
  int32_t newton_iterations = 1;  // linearised solves per step (1: SOFA's one-step form)
  double cg_tolerance = 1e-5;     // relative residual |b - A dv| / |b| a solve stops at
  int32_t cg_max_iterations = 200;
  Preconditioner preconditioner = Preconditioner::BlockJacobi;
  // Not a scenario field: the backend's choice. The products' gather on
  // this SIMD target (core/sim/implicit_gather_simd.h; the cpu backend's
  // kernel target); none: the scalar gather, the reference.
  std::optional<SimdTarget> simd_product;
};

// Throws Error(Usage) for options out of range or a combination it does not
// run (Newton iterations with friction, whose anchors advance at every
// evaluation of the contact; Newton iterations with implicit damping, whose
// system is already exact).
// `integrator` ImplicitEuler: (M + h D + h^2 K) dv = h (f - h K v).
// ImplicitDamping: (M + h D) dv = h f, the elastic and contact forces taken
// at the step's start (symplectic Euler for them, stable below the
// undamped 2/omega_max), the dampers and drag at its end. `options` are the
// implicit solver's and `threads` (>= 1) its loops' (Verlet uses none of them).
std::unique_ptr<Backend> make_reference_backend(const Model& model, const BackendTool& tool, Integrator integrator,
                                                const ImplicitOptions& options = {}, int32_t threads = 1);

}  // namespace organsim
