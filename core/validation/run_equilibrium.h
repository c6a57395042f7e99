#pragma once
// The equilibrium a run settles into under a tool held still: the force law
// as every backend steps it (springs along their current directions, the
// volume and shear terms at the current shape, the tool's contact pass with
// its sub-cell layer), not linearised at rest as static_solve.h is. Under a
// sphere pressed 5-20 % of its radius the local strains reach tens of
// percent, and the small-strain solve is then 3, 7 and 12 % stiffer than
// the run at d/R 0.05, 0.1 and 0.2 (springs alone, point contact, 8 mm
// cells; docs/validation.md, "Hertz as a run gives it"); this is what a
// quasi-static run gives, found in seconds instead of a second of
// simulated time.
//
// Found by the implicit reference (core/sim/reference_backend.h) at a step so
// long (1 s) that the mass term is negligible and each step is a Newton
// solve of f(x) = 0, with the Newton iterations' line search and the rest
// Cholesky preconditioner: the tool is lowered to its pose over the first
// steps, then held until the tool's force settles.
#include "core/model/model.h"
#include "core/sim/tool.h"

namespace organsim {

struct HeldToolEquilibrium {
  Reaction reaction;      // the tissue's force on the tool at equilibrium (a push is along +z on a top face)
  int32_t steps = 0;      // Newton-solved steps taken, the lowering's included
};

// `model`'s fixed points hold; the tool (a push) moves in a straight line
// from `from` (where it should not touch yet) to `to` and is held there.
// Settled when each of the last three steps moved the force by less than
// 1e-4 of itself (a contact alternating between two states is not
// settled). Throws Error(Numerical) after 80 steps unsettled: that happens
// with a penalty much stiffer than the tissue's points (tens of times their
// diagonal stiffness), where the layered contact's force is too
// discontinuous in the positions for Newton's steps.
HeldToolEquilibrium held_tool_equilibrium(const Model& model, const BackendTool& tool, const Vec3& from, const Vec3& to);

}  // namespace organsim
