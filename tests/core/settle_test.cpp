// time.settle: dynamic relaxation brings a block with a fixed base to rest
// under gravity, and a run started there stays there.
#include <gtest/gtest.h>

#include "core/model/model.h"
#include "core/sim/cpu_backend.h"
#include "core/run/settle.h"
#include "test_models.h"

namespace organsim {
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

}  // namespace
}  // namespace organsim
