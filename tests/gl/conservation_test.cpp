// Physical facts on the GPU, in float: a model at rest stays at rest; a free
// deformed model flying through space keeps its momentum.
#include <gtest/gtest.h>

#include "core/gl/gl_backend.h"
#include "core/util/error.h"
#include "gl_test_scenes.h"

namespace organsim {
namespace conservation_test {
namespace {

constexpr double kDt = 1e-4;  // s

Vec3 centre_of_mass(const Model& model, const std::vector<Vec3>& x) {
  Vec3 c = Vec3::Zero();
  for (int32_t i = 0; i < model.npoint(); ++i) c += model.mass[i] * x[i];
  return c / model.total_mass();
}

TEST(GlConservation, ModelAtRestStaysAtRest) {
  // Springs and volume at their rest lengths and volumes, no gravity, no
  // tool: every force is zero up to float rounding of the rest state
  // (~4e-9 m on 0.1 m coordinates). Allow 1e-6 of the diagonal (~30 ulps)
  // after 1000 steps; any spurious force term moves points far more.
  for (const bool fixed : {true, false}) {
    const Model model = gl_test::box_model(6, 6, 3, fixed, 2e4, Vec3(0, 0, 0));
    GlBackend gl(model, BackendTool{}, {});
    TickRequest request;
    request.dt = kDt;
    request.substeps = 10;
    for (int n = 0; n < 100; ++n) gl.tick(request);
    std::vector<Vec3> x;
    gl.positions(x);
    double worst = 0;
    for (int32_t i = 0; i < model.npoint(); ++i) worst = std::max(worst, (x[i] - model.rest_position[i]).norm());
    const double rel = worst / gl_test::bbox_diagonal(model);
    std::cout << (fixed ? "fixed bottom" : "free") << ": max |x - rest| = " << worst << " m (" << rel
              << " of the diagonal) after 1000 steps\n";
    EXPECT_LT(rel, 1e-6);
    EXPECT_NEAR(gl.time(), 1000 * kDt, 1e-12);
  }
}

TEST(GlConservation, FreeModelKeepsItsMomentum) {
  // No fixed points, no gravity, no drag (alpha = 0): springs, dampers and
  // volume forces are internal, so the centre of mass moves at the initial
  // velocity v0 while the deformed box wobbles. Spring pairs cancel exactly
  // in float (both ends compute the same numbers with opposite signs); tet
  // forces and the integration's rounding do not, at ~1e-7 relative per
  // step. Allow 1e-4 of |v0| for the centre-of-mass velocity after 1000
  // steps and 1e-4 of the distance travelled for its position.
  const Model model = gl_test::box_model(6, 6, 3, false, 2e4, Vec3(0, 0, 0), /*viscous_damping=*/0.0);
  GlBackend gl(model, BackendTool{}, {});
  const Vec3 v0(0.05, -0.1, 0.02);  // m/s
  const std::vector<Vec3> x = gl_test::perturbed(model, 2e-3, 3);  // 2 mm noise: strong internal forces
  std::vector<Vec3> x_prev(x.size());
  for (size_t i = 0; i < x.size(); ++i) x_prev[i] = x[i] - v0 * kDt;
  gl.set_state(x, x_prev);
  const Vec3 c0 = centre_of_mass(model, x);

  TickRequest request;
  request.dt = kDt;
  request.substeps = 10;
  for (int n = 0; n < 99; ++n) gl.tick(request);
  std::vector<Vec3> before, after;
  gl.positions(before);
  request.substeps = 1;  // one more step: velocity of the centre of mass
  gl.tick(request);
  gl.positions(after);
  const Vec3 v_com = (centre_of_mass(model, after) - centre_of_mass(model, before)) / kDt;
  const double t = 991 * kDt;
  const Vec3 travelled = centre_of_mass(model, after) - c0;
  std::cout << "v_com " << v_com.transpose() << " m/s vs v0 " << v0.transpose() << "; centre of mass off by "
            << (travelled - v0 * t).norm() << " m after " << t << " s\n";
  EXPECT_LT((v_com - v0).norm(), 1e-4 * v0.norm());
  EXPECT_LT((travelled - v0 * t).norm(), 1e-4 * v0.norm() * t);
  // The model did deform (the test is not trivially rigid motion).
  double spread = 0;
  for (int32_t i = 0; i < model.npoint(); ++i)
    spread = std::max(spread, (after[i] - x[i] - v0 * t).norm());
  EXPECT_GT(spread, 1e-4);
}

TEST(GlConservation, BlowUpIsReportedFromTheGpuWithoutAPositionReadback) {
  // dt = 20 ms is far above this box's critical step (~1 ms): the stiffest
  // mode grows by orders of magnitude per step until positions overflow.
  // The step kernel flags the first non-finite point; tick() reads the flag
  // with the reaction one tick late and throws Error(Numerical).
  const Model model = gl_test::box_model(4, 4, 2, true, 0, Vec3(0, 0, -9.81));
  GlBackend gl(model, BackendTool{}, {});
  gl.set_state(gl_test::perturbed(model, 1e-3, 5), model.rest_position);
  TickRequest request;
  request.dt = 0.02;
  request.substeps = 10;
  int ticks = 0;
  try {
    for (; ticks < 200; ++ticks) gl.tick(request);
    ADD_FAILURE() << "no blow-up reported in 200 ticks";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
    EXPECT_NE(std::string(e.what()).find("non-finite position of point"), std::string::npos) << e.what();
    std::cout << "after " << ticks << " ticks: " << e.what() << "\n";
  }
  // A stable run never trips it (the other tests run thousands of steps).
}

}  // namespace
}  // namespace conservation_test
}  // namespace organsim
