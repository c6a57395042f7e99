#pragma once
// The step as one list of named passes, computed once from the Model and the
// tool (at construction and at every rebuild) and followed by every backend:
// which compiled variant of the CPU kernels runs and whether the simd
// kernel can run it, which GL shader variants and dispatches run, and what
// `organsim run --plan` prints (the same pass names on every backend, each
// with that backend's own detail). A pass that the scene does not need is
// not in the list, and no backend executes code or touches data for it.
#include <cstdint>
#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/sim/tool.h"

namespace organsim {

enum class Pass : uint8_t {
  NodalPressure,   // every point's nodal volume and pressure, then a barrier (averaged nodal volume term)
  ShearSmoothing,  // every point's stress on its node-averaged deformation gradient, then a barrier
  Springs,         // springs and their dampers, sutures on their schedule
  Volume,          // the volume term's tet forces (per tet, or from the nodal pressures)
  ShearElement,    // the shear element's tet forces and its damper (nu < 1/4)
  Gravity,         // m g on every free point
  SurfaceContact,  // the tool against the surface triangles (broad phase, then each touching triangle's penalty)
  ToolContact,     // the tool's push penalty or pull attachments, and its reaction
  Integrate,       // position Verlet with drag
  // Implicit Euler (core/sim/reference_backend.h), in place of Integrate:
  Linearise,          // the force law's tangent blocks K, D at the step's state (and the contact's)
  ConjugateGradient,  // (M + h D + h^2 K) dv = h (f - h K v) by preconditioned CG
  VelocityUpdate,     // v += dv, x += h v on the free points (then, with Newton iterations, the passes again)
};

// How the step advances the state (docs/integrators.md): explicit position
// Verlet (the paper's, the default); backward (implicit) Euler, linearised
// once per Newton iteration; or the dampers alone implicit, the elastic
// forces explicit (symplectic Euler: dt below the undamped 2/omega_max).
enum class Integrator : uint8_t { Verlet, ImplicitEuler, ImplicitDamping };
// "verlet", "implicit_euler", "implicit_damping".
const char* integrator_name(Integrator integrator);
// Whether a step solves a linear system (core/sim/reference_backend.h).
inline bool solves_implicitly(Integrator integrator) { return integrator != Integrator::Verlet; }

// The per-tet term of a model: at most one of these (core/model/stiffness.h).
enum class ElementTerm : uint8_t { None, TetVolume, NodalVolume, ShearElement, SmoothedShear };
// The tool pass of a step: absent, or the tool's mode (a pushing tool's
// penalty on the points, or its surface contact's forces on them).
enum class ToolTerm : uint8_t { None, Push, Pull, Surface };

struct StepPlan {
  ElementTerm element = ElementTerm::None;
  bool gravity = false;
  ToolTerm tool = ToolTerm::None;  // the scene's tool; a tick without contact skips it
  Integrator integrator = Integrator::Verlet;
  int32_t sutures = 0;             // springs that pull only, on a schedule
  std::vector<Pass> passes;        // in order of execution

  bool has(Pass pass) const;
  bool volume() const { return element == ElementTerm::TetVolume || element == ElementTerm::NodalVolume; }
  bool shear() const { return element == ElementTerm::ShearElement || element == ElementTerm::SmoothedShear; }
};

StepPlan make_step_plan(const Model& model, const BackendTool& tool, Integrator integrator = Integrator::Verlet);

// "nodal-pressure", "shear-smoothing", "springs", "volume", "shear-element",
// "gravity", "surface-contact", "tool-contact", "integrate", "linearise",
// "conjugate-gradient", "velocity-update".
const char* pass_name(Pass pass);

}  // namespace organsim
