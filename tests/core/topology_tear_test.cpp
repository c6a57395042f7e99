// Tearing (issue 8): no separation below the threshold however long, a
// separation after exactly the stated number of ticks above it, the same on
// every run; scenarios/bar_tear.json comes apart in two.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/mesh/mesh_io.h"
#include "core/sim/cpu_backend.h"
#include "core/run/run.h"
#include "core/topology/tear.h"
#include "core/topology/topology_editor.h"
#include "tests/core/topology_test_util.h"

namespace organsim {
namespace topology_tear_test {
namespace {

namespace fs = std::filesystem;

Model bar_model() {
  Material m;
  m.density = 1000;
  m.young_modulus = 5000;
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3(0.06, 0.015, 0.015), 12, 3, 3), m, {});
}

// Rest positions stretched along x by 1 + e: springs along x reach strain e,
// the others less.
std::vector<Vec3> stretched(const Model& model, double e) {
  std::vector<Vec3> x = model.rest_position;
  for (Vec3& p : x) p.x() *= 1 + e;
  return x;
}

TEST(Tear, NothingSeparatesJustBelowTheThreshold) {
  const Model model = bar_model();
  const TetFaces faces = build_tet_faces(model.tet_points);
  const std::vector<uint8_t> separated(faces.nface(), 0);
  TearDetector tear({0.5, 3, 4});
  const auto x = stretched(model, 0.98 * 0.5);
  for (int tick = 0; tick < 10000; ++tick) ASSERT_TRUE(tear.update(model, x, faces, separated).empty()) << tick;
}

TEST(Tear, SeparatesAfterTheStatedTicksAboveTheThresholdAndAlwaysTheSameFaces) {
  const Model model = bar_model();
  const TetFaces faces = build_tet_faces(model.tet_points);
  const std::vector<uint8_t> separated(faces.nface(), 0);
  std::vector<int32_t> first;
  for (int run = 0; run < 2; ++run) {
    TearDetector tear({0.5, 3, 4});
    const auto x = stretched(model, 1.05 * 0.5);
    EXPECT_TRUE(tear.update(model, x, faces, separated).empty());  // tick 1
    EXPECT_TRUE(tear.update(model, x, faces, separated).empty());  // tick 2
    const auto torn = tear.update(model, x, faces, separated);     // tick 3: the stated number
    ASSERT_EQ(torn.size(), 4u);                                    // capped per tick
    // Each torn face is perpendicular to the stretch (normal along x).
    for (int32_t f : torn) {
      const Tri v = tet_face(model.tet_points[faces.tets[f][0]], faces.local[f][0]);
      const Vec3 n = (x[v[1]] - x[v[0]]).cross(x[v[2]] - x[v[0]]).normalized();
      EXPECT_NEAR(std::abs(n.x()), 1.0, 1e-12) << "face " << f;
    }
    if (run == 0) first = torn;
    else EXPECT_EQ(torn, first);
  }
}

TEST(Tear, BarTearScenarioComesApartInTwo) {
  const fs::path file = fs::path(ORGANSIM_SOURCE_DIR) / "scenarios" / "bar_tear.json";
  const Scenario s = load_scenario(file);
  ASSERT_TRUE(s.events.tear.has_value());
  const Model model = build_model(read_tet_mesh(s.mesh.path), s.material, model_options(s), "bar");
  auto backend = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  testing::TopologyRecorder recorder;
  RunOptions options;
  options.outdir = fs::path(ORGANSIM_TEST_TMP) / "bar_tear";
  options.observers = {&recorder};
  const RunResult result = run_scenario(s, model, *backend, options);
  ASSERT_TRUE(result.meta.completed);
  ASSERT_TRUE(recorder.last.has_value());
  EXPECT_EQ(testing::topology_problems(*recorder.last), "");
  int32_t components = 0;
  testing::point_components(*recorder.last, &components);
  EXPECT_GE(components, 2);
  EXPECT_NEAR(recorder.last->total_mass(), model.total_mass(), 1e-12 * model.total_mass());
  // Once torn the grasper pulls nothing: the force at the end of the pull is
  // a small fraction of its peak before the tear. Measured 3.7 % at 0.55 s
  // with poisson_ratio 0.45: the torn-off piece still rings along the pull
  // (about 20 Hz, its axial mode, lightly damped), where the stiffer per-tet
  // volume_modulus material's had died down to 0.3 %.
  double peak = 0;
  for (const Vec3& f : result.samples.force) peak = std::max(peak, f.norm());
  const size_t before_stop = static_cast<size_t>(0.55 / s.time.tick());
  EXPECT_LT(result.samples.force[before_stop].norm(), 0.05 * peak);
}

}  // namespace
}  // namespace topology_tear_test
}  // namespace organsim
