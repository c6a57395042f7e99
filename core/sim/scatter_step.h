#pragma once
// The plain per-spring / per-tet scatter step that most mass-spring codes
// run (Vega FEM's explicit integrator has this shape): one thread, the
// Model's own arrays, a force array zeroed and filled each step, then
// integration. Written for clarity, not speed: `organsim bench` times it on
// the same model and precision as the real step and prints the speedup.
// Same physics and state as the CPU backend (displacement u and step
// increment d, docs/architecture.md "Model and State").
#include <vector>

#include "core/model/model.h"

namespace organsim {

template <class Real>
class ScatterStep {
 public:
  explicit ScatterStep(const Model& model);
  // One step of dt (springs + dampers, volume (per tet or nodal) or the shear
  // element and its damper if the model has it, gravity, position Verlet
  // with drag); no tool.
  void step(double dt);
  // Current positions x_t (internal numbering).
  void positions(std::vector<Vec3>& out) const;

 private:
  using V3 = Eigen::Matrix<Real, 3, 1>;
  using M3 = Eigen::Matrix<Real, 3, 3>;
  const Model& model_;
  std::vector<V3> rest_, u_, d_, force_;
  std::vector<Real> nodal_;  // nodal pressures of the nodal volume term (npoint; empty without it)
  std::vector<M3> stress_;   // smoothed shear element: sum of k_t H_t, then P(Fbar), per point (npoint; else empty)
};

extern template class ScatterStep<float>;
extern template class ScatterStep<double>;

}  // namespace organsim
