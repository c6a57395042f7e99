#include "core/sim/step_plan.h"

#include <algorithm>

namespace organsim {

bool StepPlan::has(Pass pass) const { return std::find(passes.begin(), passes.end(), pass) != passes.end(); }

StepPlan make_step_plan(const Model& model, const BackendTool& tool, Integrator integrator) {
  StepPlan plan;
  plan.integrator = integrator;
  plan.element = model.has_nodal_volume()    ? ElementTerm::NodalVolume
                 : model.has_volume()        ? ElementTerm::TetVolume
                 : model.has_smoothed_shear() ? ElementTerm::SmoothedShear
                 : model.has_shear_element() ? ElementTerm::ShearElement
                                             : ElementTerm::None;
  plan.gravity = model.has_gravity();
  plan.tool = !tool.present                        ? ToolTerm::None
              : tool.mode == ToolMode::Pull           ? ToolTerm::Pull
              : tool.contact == ToolContact::Surface ? ToolTerm::Surface
                                                     : ToolTerm::Push;
  plan.sutures = model.nsuture();
  // Per-point passes whose results the force passes read come first, each
  // ending at a barrier; the force passes and the integration then run fused.
  if (plan.element == ElementTerm::NodalVolume) plan.passes.push_back(Pass::NodalPressure);
  if (plan.element == ElementTerm::SmoothedShear) plan.passes.push_back(Pass::ShearSmoothing);
  // The surface contact's per-point forces, which the tool pass adds.
  if (plan.tool == ToolTerm::Surface) plan.passes.push_back(Pass::SurfaceContact);
  plan.passes.push_back(Pass::Springs);
  if (plan.volume()) plan.passes.push_back(Pass::Volume);
  if (plan.shear()) plan.passes.push_back(Pass::ShearElement);
  if (plan.gravity) plan.passes.push_back(Pass::Gravity);
  if (plan.tool != ToolTerm::None) plan.passes.push_back(Pass::ToolContact);
  if (integrator == Integrator::Verlet) {
    plan.passes.push_back(Pass::Integrate);
  } else {
    for (Pass pass : {Pass::Linearise, Pass::ConjugateGradient, Pass::VelocityUpdate}) plan.passes.push_back(pass);
  }
  return plan;
}

const char* pass_name(Pass pass) {
  switch (pass) {
    case Pass::NodalPressure: return "nodal-pressure";
    case Pass::ShearSmoothing: return "shear-smoothing";
    case Pass::Springs: return "springs";
    case Pass::Volume: return "volume";
    case Pass::ShearElement: return "shear-element";
    case Pass::Gravity: return "gravity";
    case Pass::SurfaceContact: return "surface-contact";
    case Pass::ToolContact: return "tool-contact";
    case Pass::Integrate: return "integrate";
    case Pass::Linearise: return "linearise";
    case Pass::ConjugateGradient: return "conjugate-gradient";
    case Pass::VelocityUpdate: return "velocity-update";
  }
  return "?";
}

const char* integrator_name(Integrator integrator) {
  switch (integrator) {
    case Integrator::Verlet: return "verlet";
    case Integrator::ImplicitEuler: return "implicit_euler";
    case Integrator::ImplicitDamping: return "implicit_damping";
  }
  return "?";
}

}  // namespace organsim
