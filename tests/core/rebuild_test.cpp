// The rebuild path every topology change goes through: rebuild_model makes a
// new Model version (ids kept, points appended) and Backend::rebuild carries
// the State over. Cut-specific geometry (blades, components) is tested with
// the topology code; here the change is made by hand.
#include <gtest/gtest.h>

#include <numeric>

#include "core/model/model_rebuild.h"
#include "core/sim/cpu_backend.h"
#include "core/util/error.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace rebuild_test {
namespace {

// A 4 x 4 x 4 cube box of 4 cm; jitter moves interior points off the grid.
Model box(bool volume, const Vec3& gravity, bool fixed_base, double jitter = 0) {
  Material material;
  material.young_modulus = 5000;
  material.volume_modulus = volume ? 20000 : 0;
  material.viscous_damping = 0.5;
  ModelOptions options;
  options.gravity = gravity;
  options.chunk_size = 16;  // several chunks on a small model (one register of AVX-512 floats each)
  options.sort_window = 16;
  if (fixed_base) {
    FixedSelector base;
    base.kind = FixedSelector::Kind::Plane;
    base.point = Vec3(0, 0, 1e-9);
    base.normal = Vec3(0, 0, -1);
    options.fixed.push_back(base);
  }
  return build_model(testing::jittered_box(4, 0.04, jitter, 3), material, options);
}

std::vector<Vec3> positions_of(const Backend& backend) {
  std::vector<Vec3> x;
  backend.positions(x);
  return x;
}

TEST(Rebuild, IdentityChangeRebuildsTheSameModel) {
  const Model model = box(true, Vec3(0, 0, -9.81), true, 0.2);
  const Model same = rebuild_model(model, {model.tet_points, {}});
  EXPECT_EQ(same.version, 1);
  EXPECT_EQ(same.spring_ends, model.spring_ends);
  EXPECT_EQ(same.spring_k, model.spring_k);
  EXPECT_EQ(same.mass, model.mass);
  EXPECT_EQ(same.fixed, model.fixed);
  EXPECT_EQ(same.tet_k, model.tet_k);
  EXPECT_EQ(same.layout.springs.item, model.layout.springs.item);
  EXPECT_EQ(same.layout.tets.item, model.layout.tets.item);
}

// A backend rebuilt mid-run from an unchanged topology steps on exactly as
// one that never rebuilt: the state carries over bit for bit. A rebuild
// that did nothing would pass that too, so the backend is then rebuilt into
// the same topology with every point fixed (1/m = 0): stepping that version,
// no point may move at all.
TEST(Rebuild, IdentityRebuildKeepsTheTrajectoryBitIdentical) {
  const Model model = box(true, Vec3(0, 0, -9.81), true, 0.2);
  const Model same = rebuild_model(model, {model.tet_points, {}});
  Model frozen = same;
  std::fill(frozen.fixed.begin(), frozen.fixed.end(), 1);
  std::fill(frozen.inv_mass.begin(), frozen.inv_mass.end(), 0.0);
  for (Precision precision : {Precision::Double, Precision::Float}) {
    auto straight = make_cpu_backend(model, {}, {precision, 1});
    auto rebuilt = make_cpu_backend(model, {}, {precision, 1});
    testing::run_ticks(*straight, 20, 1e-4, 5);
    testing::run_ticks(*rebuilt, 10, 1e-4, 5);
    rebuilt->rebuild(same);
    testing::run_ticks(*rebuilt, 10, 1e-4, 5);
    const auto a = positions_of(*straight), b = positions_of(*rebuilt);
    ASSERT_EQ(a.size(), b.size());
    double moved = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i], b[i]) << "point " << i;
      moved = std::max(moved, (a[i] - model.rest_position[i]).norm());
    }
    EXPECT_GT(moved, 1e-6);  // the run did something
    rebuilt->rebuild(frozen);
    testing::run_ticks(*rebuilt, 5, 1e-4, 5);
    EXPECT_EQ(positions_of(*rebuilt), b);
  }
}

TEST(Rebuild, SplitConservesMassAndSeparatesTheSides) {
  const Model model = box(true, Vec3(0, 0, -9.81), true);
  const TopologyChange change = testing::split_across_plane_x(model, 0.02);
  ASSERT_EQ(change.appended_origin.size(), 25u);  // the 5 x 5 points of the plane x = 0.02
  const Model cut = rebuild_model(model, change);
  EXPECT_EQ(cut.npoint(), model.npoint() + 25);
  EXPECT_EQ(cut.ntet(), model.ntet());
  // Total mass to round-off: the same quarter-tet masses, summed elsewhere.
  EXPECT_NEAR(cut.total_mass(), model.total_mass(), 1e-12 * model.total_mass());
  EXPECT_EQ(cut.rest_volume(), model.rest_volume());
  // No spring joins the two sides; each side's springs carry only its tets'
  // share. A spring's k is a sum over the tets around its edge (linear in
  // their volumes), so a split that hands each side its tets' share keeps
  // the total, to round-off of the re-summed shares (1e-12 relative); a
  // split spring that kept its whole k on both sides would add the shares
  // of the other side's tets.
  for (const Edge& e : cut.spring_ends) {
    const bool a_right = e[0] >= model.npoint() || cut.rest_position[e[0]].x() > 0.02 + 1e-9;
    const bool b_right = e[1] >= model.npoint() || cut.rest_position[e[1]].x() > 0.02 + 1e-9;
    const bool a_left = e[0] < model.npoint() && cut.rest_position[e[0]].x() < 0.02 + 1e-9;
    const bool b_left = e[1] < model.npoint() && cut.rest_position[e[1]].x() < 0.02 + 1e-9;
    EXPECT_TRUE((a_right && b_right) || (a_left && b_left)) << e[0] << "-" << e[1];
  }
  const double k_before = std::accumulate(model.spring_k.begin(), model.spring_k.end(), 0.0);
  EXPECT_NEAR(std::accumulate(cut.spring_k.begin(), cut.spring_k.end(), 0.0), k_before, 1e-12 * k_before);
  // Copies keep their origin's rest position, fixed flag and output number
  // from the mesh's point count upward.
  for (int32_t p = model.npoint(); p < cut.npoint(); ++p) {
    const int32_t o = cut.origin[p];
    EXPECT_EQ(cut.rest_position[p], model.rest_position[o]);
    EXPECT_EQ(cut.fixed[p], model.fixed[o]);
    EXPECT_EQ(cut.input_of_internal[p], p);
    EXPECT_EQ(cut.internal_of_input[p], p);
    EXPECT_NEAR(cut.mass[p] + cut.mass[o], model.mass[o], 1e-15);
  }
}

// Every point, copies included, moving at one velocity with no force: one
// more tick moves each by exactly v t. A copy that lost its origin's
// increment d (a velocity jump at the cut) would lag behind.
TEST(Rebuild, CopiesStartWithTheirOriginsPositionAndVelocity) {
  const Model model = box(true, Vec3::Zero(), false);
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.02));
  const Vec3 offset(0.003, -0.001, 0.002), velocity(0.2, 0.1, -0.3);
  const double dt = 1e-4;
  std::vector<Vec3> x(model.rest_position), x_prev(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] += offset;
    x_prev[i] = x[i] - velocity * dt;
  }
  for (Precision precision : {Precision::Double, Precision::Float}) {
    auto backend = make_cpu_backend(model, {}, {precision, 1});
    backend->set_state(x, x_prev);
    backend->rebuild(cut);
    const auto after_rebuild = positions_of(*backend);
    ASSERT_EQ(after_rebuild.size(), static_cast<size_t>(cut.npoint()));
    testing::run_ticks(*backend, 1, dt, 10);
    const auto moved = positions_of(*backend);
    // Viscous drag (0.5 1/s) slows every point alike: d' = (1 - alpha dt) d.
    double travel = 0, step = dt * velocity.norm();
    for (int s = 0; s < 10; ++s) {
      step *= 1 - model.viscous_damping * dt;
      travel += step;
    }
    // Double: rounding of 5 cm coordinates (~1e-17 m) over 10 steps. Float
    // keeps u and d (not x), so ~1e-9 m: still 1e-4 of the 0.3 mm travelled.
    const double tol = precision == Precision::Double ? 1e-14 : 1e-8;
    for (int32_t p = 0; p < cut.npoint(); ++p) {
      EXPECT_NEAR((after_rebuild[p] - x[cut.origin[p]]).norm(), 0, tol) << "point " << p;
      const Vec3 expected = cut.rest_position[p] + offset + travel * velocity.normalized();
      EXPECT_NEAR((moved[p] - expected).norm(), 0, tol) << "point " << p;
    }
  }
}

TEST(Rebuild, MalformedChangesAreRefused) {
  const Model model = box(false, Vec3::Zero(), false);
  TopologyChange wrong_count{{model.tet_points.begin(), model.tet_points.end() - 1}, {}};
  EXPECT_THROW(rebuild_model(model, wrong_count), Error);
  TopologyChange bad_origin{model.tet_points, {model.npoint()}};
  EXPECT_THROW(rebuild_model(model, bad_origin), Error);
  // A vertex replaced by a point that is not its copy would change the rest volume.
  TopologyChange not_a_copy{model.tet_points, {}};
  std::swap(not_a_copy.tet_points[0][0], not_a_copy.tet_points[0][1]);
  EXPECT_THROW(rebuild_model(model, not_a_copy), Error);
}

}  // namespace
}  // namespace rebuild_test
}  // namespace organsim
