// time.settle: dynamic relaxation brings a block with a fixed base to rest
// under gravity, and a run started there stays there.
#include <gtest/gtest.h>

#include "core/model/model.h"
#include "core/sim/cpu_backend.h"
#include "core/run/prepare_run.h"
#include "core/run/settle.h"
#include "core/stability/critical_step.h"
#include "test_models.h"

namespace organsim {
namespace settle_test {
namespace {

// `seconds` of settling at dt 1e-4 s, 10 substeps, one thread.
SettleOptions settle_options(double seconds) {
  SettleOptions o;
  o.seconds = seconds;
  o.dt = 1e-4;
  o.substeps = 10;
  o.threads = 1;
  return o;
}

// A soft 4 x 4 x 4 cm block, base fixed, under gravity: it sags visibly.
Model sagging_block() {
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.04, 0.04, 0.04), 4, 4, 4);
  Material material;
  material.density = 1000;
  material.young_modulus = 3000;
  material.viscous_damping = 1;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  FixedSelector base;
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 0.001);
  base.normal = Vec3(0, 0, -1);
  options.fixed = {base};
  return build_model(mesh, material, options);
}

double largest_move(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double m = 0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, (a[i] - b[i]).norm());
  return m;
}

TEST(Settle, BlockComesToRestAndStaysThere) {
  const Model model = sagging_block();
  const SettleResult settled = settle(model, settle_options(2.0));
  EXPECT_TRUE(settled.converged) << describe(settled);
  EXPECT_LT(settled.residual_relative, 1e-4) << describe(settled);
  EXPECT_GT(settled.max_displacement, 1e-3) << "the block should sag by millimetres";
  EXPECT_LT(settled.seconds, 2.0);

  // From the settled state (zero velocity) 50 ms of the run move no point by
  // more than 1 % of the sag; from the rest shape the same run moves it by
  // more than half the sag (it is falling into place).
  const auto moved_over_run = [&](const std::vector<Vec3>& start) {
    auto backend = make_cpu_backend(model, BackendTool{}, {Precision::Double, 1});
    backend->set_state(start, start);
    testing::run_ticks(*backend, 50, 1e-4, 10);
    std::vector<Vec3> x;
    backend->positions(x);
    return largest_move(x, start);
  };
  EXPECT_LT(moved_over_run(settled.positions), 0.01 * settled.max_displacement);
  EXPECT_GT(moved_over_run(model.rest_position), 0.5 * settled.max_displacement);
}

TEST(Settle, WithoutGravityTheRestShapeIsTheEquilibrium) {
  Model model = sagging_block();
  model.gravity = Vec3::Zero();
  const SettleResult settled = settle(model, settle_options(0.05));
  EXPECT_TRUE(settled.converged);
  EXPECT_LT(settled.max_displacement, 1e-12);  // nothing pulls: round-off only
}

// The equilibrium depends on no integrator or step: implicit Euler at 10 ms
// (several dt_crit) settles to the same sag as Verlet, within 1 %.
TEST(Settle, ImplicitEulerSettlesToVerletsEquilibrium) {
  const Model model = sagging_block();
  const SettleResult verlet = settle(model, settle_options(2.0));
  SettleOptions o = settle_options(2.0);
  o.dt = 1e-2;
  o.substeps = 1;
  o.integrator = Integrator::ImplicitEuler;
  ASSERT_GT(o.dt, estimate_critical_step(model).dt_crit);
  const SettleResult implicit = settle(model, o);
  EXPECT_TRUE(implicit.converged) << describe(implicit);
  EXPECT_LT(largest_move(implicit.positions, verlet.positions), 0.01 * verlet.max_displacement);
}

// A scenario whose Verlet step exceeds dt_crit (the run refuses it after
// the start is prepared) still settles at a stable step: a finite start at
// the same equilibrium, not a divergence into NaN.
TEST(Settle, AnUnstableScenarioStepSettlesAtAStableOne) {
  const Model model = sagging_block();
  Scenario s;
  s.time.settle = 2.0;
  s.time.substeps = 1;
  s.time.dt = 3 * estimate_critical_step(model).dt_crit;
  const PreparedRun prepared = prepare_run(s, model, {true, 1});
  ASSERT_TRUE(prepared.settled.has_value());
  for (const Vec3& p : prepared.settled->positions) ASSERT_TRUE(p.allFinite());
  EXPECT_TRUE(prepared.settled->converged) << describe(*prepared.settled);
  const SettleResult stable = settle(model, settle_options(2.0));
  EXPECT_LT(largest_move(prepared.settled->positions, stable.positions), 0.01 * stable.max_displacement);
}

}  // namespace
}  // namespace settle_test
}  // namespace organsim
