// The study's maths: trajectory comparison (aligned by tick and latency) and
// the Pareto front.
#include <gtest/gtest.h>

#include <cmath>

#include "core/stability/study.h"

namespace organsim {
namespace stability_study_test {
namespace {

TEST(StabilityStudy, CompareAlignsTicksAndLatency) {
  Trajectory ref, run;
  ref.ticks = {1, 3, 5};
  run.ticks = {3, 5, 7};  // tick 7 has no reference: ignored
  for (int i = 0; i < 3; ++i) ref.positions.push_back({Vec3(0, 0, 0), Vec3(1, 0, 0)});
  run.positions = {{Vec3(0, 0, 0), Vec3(1, 0, 0)}, {Vec3(0.3, 0, 0), Vec3(1, 0.4, 0)}, {Vec3(9, 9, 9), Vec3(9, 9, 9)}};
  // Forces: the run reports one tick late (latency 1) but is otherwise exact but for tick 2.
  ref.force = {Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(4, 0, 0)};
  run.latency_ticks = 1;
  run.force = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(4, 3, 0)};
  const StudyErrors e = compare_trajectories(run, ref, 2.0);
  EXPECT_EQ(e.samples, 2);
  EXPECT_DOUBLE_EQ(e.position_max, 0.4 / 2.0);
  // RMS over 4 point samples of d/diag: (0, 0, 0.15, 0.2).
  EXPECT_NEAR(e.position_rms, std::sqrt((0.15 * 0.15 + 0.2 * 0.2) / 4), 1e-15);
  EXPECT_EQ(e.ticks, 3);
  EXPECT_NEAR(e.force_rms, std::sqrt(9.0 / 3) / 4.0, 1e-15);  // |dF| = 3 on one of 3 ticks, peak 4
}

TEST(StabilityStudy, ParetoFront) {
  // cost, error: (1, 5) (2, 3) (3, 4) dominated by (2, 3), (4, 1), unstable (NaN).
  const std::vector<double> cost{1, 2, 3, 4, NAN};
  const std::vector<double> error{5, 3, 4, 1, 0.1};
  const std::vector<bool> front = pareto_front(cost, error);
  EXPECT_EQ(front, (std::vector<bool>{true, true, false, true, false}));
}

}  // namespace
}  // namespace stability_study_test
}  // namespace organsim
