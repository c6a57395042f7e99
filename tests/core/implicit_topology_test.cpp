// Implicit Euler across topology changes: a hanging block cut right through
// under implicit Euler drops its lower part at g with its mass kept, and a
// sutured beam's gap closes with every position finite, with block Jacobi
// and with the two-level preconditioner (whose coarse space each new Model
// version rebuilds). The backend is rebuilt through the same prepare/adopt
// path as the CPU backend's.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/run/run.h"
#include "core/sim/reference_backend.h"
#include "tests/core/suture_test_util.h"
#include "tests/core/topology_test_util.h"

namespace organsim {
namespace implicit_topology_test {
namespace {

namespace fs = std::filesystem;

// One implicit Euler step per 1 ms tick.
void implicit_at_the_tick(Scenario& s, Preconditioner preconditioner) {
  s.time.implicit.preconditioner = preconditioner;
  s.time.dt = s.time.tick();
  s.time.substeps = 1;
  s.time.integrator = Integrator::ImplicitEuler;
  s.time.implicit.cg_tolerance = 1e-8;  // momentum balance within 1e-8 of each step's
}

RunResult run_implicit(const Scenario& s, const Model& model, testing::TopologyRecorder& rec, const std::string& name) {
  auto backend = make_reference_backend(model, backend_tool(s), s.time.integrator, s.time.implicit);
  RunOptions run;
  run.outdir = fs::path(ORGANSIM_TEST_TMP) / name;
  run.observers = {&rec};
  return run_scenario(s, model, *backend, run);
}

// The hanging block of topology_test_util.h (4 cm, no drag, cut through the
// plane z = 2 cm at t = 20 ms).
class ImplicitTopology : public ::testing::TestWithParam<Preconditioner> {};

TEST_P(ImplicitTopology, ABlockCutThroughDropsItsLowerPartAtGWithItsMassKept) {
  Scenario s = testing::hanging_block();
  implicit_at_the_tick(s, GetParam());
  const Model model = testing::block_model(s);
  testing::TopologyRecorder rec;
  rec.keep_positions = true;
  run_implicit(s, model, rec, std::string("implicit_block_cut_") + preconditioner_name(GetParam()));
  ASSERT_EQ(rec.changes, 1);
  const Model& cut_model = *rec.last;
  EXPECT_EQ(testing::topology_problems(cut_model), "");
  EXPECT_NEAR(cut_model.total_mass(), model.total_mass(), 1e-12 * model.total_mass());
  int32_t components = 0;
  const auto label = testing::point_components(cut_model, &components);
  ASSERT_EQ(components, 2);
  int32_t held_label = -1;
  for (int32_t p = 0; p < cut_model.npoint(); ++p)
    if (cut_model.fixed[p]) held_label = label[p];
  double mass = 0;
  for (int32_t p = 0; p < cut_model.npoint(); ++p)
    if (label[p] != held_label) mass += cut_model.mass[p];
  ASSERT_EQ(rec.x.size(), 60u);
  for (const auto& tick : rec.x)
    for (const Vec3& p : tick) ASSERT_TRUE(p.allFinite());
  auto com_z = [&](size_t tick) {
    double z = 0;
    for (int32_t p = 0; p < cut_model.npoint(); ++p)
      if (label[p] != held_label) z += cut_model.mass[p] * rec.x[tick][p].z();
    return z / mass;
  };
  // The internal forces and their linearisation sum to zero over the freed
  // part (each is a difference between its ends), so backward Euler too
  // drops its centre of mass at g: 1 %, as for Verlet.
  const size_t a = 25, b = 42, c = 59;
  const double h = (b - a) * s.time.tick();
  EXPECT_NEAR((com_z(c) - 2 * com_z(b) + com_z(a)) / (h * h), -9.81, 0.01 * 9.81);
}

// The sutured beam of suture_test.cpp (cut in its first 10 ms, sutured at 0.3 s):
// under implicit Euler the gap closes to a tenth of its opening and every
// position stays finite; the sutures add no mass.
TEST_P(ImplicitTopology, ASuturedGapClosesWithEveryPositionFinite) {
  Scenario s = testing::sutured_beam(0.3, 1.3);
  implicit_at_the_tick(s, GetParam());
  const Model model = testing::beam_model(s);
  testing::TopologyRecorder rec;
  rec.keep_positions = true;
  run_implicit(s, model, rec, std::string("implicit_suture_beam_") + preconditioner_name(GetParam()));
  ASSERT_TRUE(rec.last.has_value());
  const Model& last = *rec.last;
  ASSERT_GT(last.nsuture(), 2);
  EXPECT_NEAR(last.total_mass(), model.total_mass(), 1e-12 * model.total_mass());
  const size_t tie = 300;
  const double opening = testing::cut_gap(last, rec.x[tie - 1]);
  ASSERT_GT(opening, 2e-3);
  const size_t closed = tie + static_cast<size_t>(1e3 * (opening / 0.05 + 0.2));
  ASSERT_LT(closed, rec.x.size());
  for (size_t i = 0; i < rec.x.size(); ++i) {
    for (const Vec3& p : rec.x[i]) ASSERT_TRUE(p.allFinite()) << "tick " << i;
    if (i >= closed) {
      EXPECT_LE(testing::cut_gap(last, rec.x[i]), 0.1 * opening) << "t = " << (i + 1) * 1e-3 << " s";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Preconditioners, ImplicitTopology,
                         ::testing::Values(Preconditioner::BlockJacobi, Preconditioner::TwoLevel),
                         [](const ::testing::TestParamInfo<Preconditioner>& info) {
                           return std::string(preconditioner_name(info.param));
                         });

}  // namespace
}  // namespace implicit_topology_test
}  // namespace organsim
