// The per-point gather (SELL-C-sigma layout) against the naive per-spring /
// per-tet scatter, layout invariants, numbering, determinism and precision.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace gather_test {
namespace {

Model random_model(int32_t chunk, int32_t window) {
  Material material;
  material.density = 1000;
  material.young_modulus = 4000;
  material.spring_damping_time = 0.01;
  material.viscous_damping = 0;
  material.volume_modulus = 30000;
  ModelOptions options;
  options.gravity = Vec3(0.3, -1.0, -9.81);
  options.chunk_size = chunk;
  options.sort_window = window;
  FixedSelector base;  // hold the base so the tool has something to push
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-9);
  base.normal = Vec3(0, 0, -1);
  options.fixed.push_back(base);
  return build_model(testing::jittered_box(5, 0.05, 0.25, 11), material, options);
}

TEST(Gather, OneStepMatchesNaiveScatter) {
  // Chunks of 16 points (one register of the widest target's floats) sorted
  // in windows of 16, and unsorted.
  for (auto [chunk, window] : {std::pair{64, 256}, std::pair{16, 16}, std::pair{16, 1 << 30}}) {
    const Model model = random_model(chunk, window);
    std::mt19937 rng(5);
    std::normal_distribution<double> noise(0, 1);
    const double dt = 1e-4;
    std::vector<Vec3> x = model.rest_position, x_prev(x.size()), v(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
      x[i] += 1e-3 * Vec3(noise(rng), noise(rng), noise(rng));
      v[i] = 0.2 * Vec3(noise(rng), noise(rng), noise(rng));
      x_prev[i] = x[i] - dt * v[i];
    }
    std::vector<Vec3> force;
    reference_internal_forces(model, x, v, force);
    auto backend = make_cpu_backend(model, {}, testing::one_thread());
    backend->set_state(x, x_prev);
    testing::run_ticks(*backend, 1, dt, 1);
    std::vector<Vec3> after;
    backend->positions(after);
    double scale = 0;
    for (const Vec3& f : force) scale = std::max(scale, f.norm());
    for (int i = 0; i < model.npoint(); ++i) {
      const Vec3 expected = model.fixed[i] ? x[i] : Vec3(x[i] + (x[i] - x_prev[i]) + dt * dt * model.inv_mass[i] * force[i]);
      // The two sums add the same terms in another order: double rounding,
      // ~1e-16 of x (5 cm) plus ~1e-13 of the force increment.
      EXPECT_LT((after[i] - expected).norm(), 1e-15 + 1e-12 * dt * dt * model.inv_mass[i] * scale)
          << "point " << i << " chunk " << chunk;
    }
  }
}

TEST(Gather, LayoutHoldsEachSpringTwiceAndEachTetFourTimes) {
  const Model model = random_model(64, 256);
  const auto& L = model.layout;
  std::vector<int> spring_seen(model.nspring(), 0), tet_seen(model.ntet(), 0);
  for (int32_t c = 0; c < L.nchunk; ++c) {
    for (int32_t e = L.springs.chunk_offset[c]; e < L.springs.chunk_offset[c + 1]; ++e) {
      if (L.springs.item[e] < 0) continue;
      const int32_t p = c * L.chunk_size + (e - L.springs.chunk_offset[c]) % L.chunk_size;
      const auto [a, b] = model.spring_ends[L.springs.item[e]];
      EXPECT_TRUE(p == a || p == b);
      EXPECT_EQ(L.spring_other[e], a + b - p);
      ++spring_seen[L.springs.item[e]];
    }
    for (int32_t e = L.tets.chunk_offset[c]; e < L.tets.chunk_offset[c + 1]; ++e) {
      if (L.tets.item[e] < 0) continue;
      const int32_t p = c * L.chunk_size + (e - L.tets.chunk_offset[c]) % L.chunk_size;
      const auto& o = L.tet_others[e];
      const auto& x = model.rest_position;
      // "The first point is inferred": (p, others) keeps the positive orientation.
      EXPECT_GT(signed_volume(x[p], x[o[0]], x[o[1]], x[o[2]]), 0);
      ++tet_seen[L.tets.item[e]];
    }
  }
  for (int s : spring_seen) EXPECT_EQ(s, 2);
  for (int t : tet_seen) EXPECT_EQ(t, 4);
  // Valence is non-increasing inside each sort window (the paper's ordering).
  for (int32_t p = 1; p < model.npoint(); ++p)
    if (p % L.sort_window != 0) {
      EXPECT_GE(L.springs.count[p - 1], L.springs.count[p]);
    }
}

TEST(Gather, InternalNumberingMapsBackToInput) {
  const TetMesh mesh = testing::jittered_box(5, 0.05, 0.25, 11);
  const Model model = random_model(64, 256);
  ASSERT_EQ(model.npoint(), static_cast<int32_t>(mesh.points.size()));
  for (int32_t i = 0; i < model.npoint(); ++i) {
    EXPECT_EQ(model.rest_position[model.internal_of_input[i]], mesh.points[i]);
    EXPECT_EQ(model.input_of_internal[model.internal_of_input[i]], i);
  }
  // Springs are exactly the unique tet edges, mapped back to input ids.
  std::map<Edge, int> edges;
  for (const Tet& t : mesh.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edges[{std::min(t[i], t[j]), std::max(t[i], t[j])}] = 1;
  ASSERT_EQ(edges.size(), static_cast<size_t>(model.nspring()));
  for (const Edge& e : model.spring_ends) {
    const int32_t a = model.input_of_internal[e[0]], b = model.input_of_internal[e[1]];
    EXPECT_TRUE(edges.count({std::min(a, b), std::max(a, b)}));
  }
}

std::vector<Vec3> pushed_run(const Model& model, const CpuBackendOptions& options, Reaction& last) {
  BackendTool tool{true, ToolMode::Push, 0.02, 500};
  auto backend = make_cpu_backend(model, tool, options);
  TickRequest request;
  request.dt = 5e-5;
  request.substeps = 20;
  request.tool_active = true;
  for (int i = 0; i < 100; ++i) {
    request.tool_from = Vec3(0.025, 0.025, 0.07 - 0.0002 * i);
    request.tool_to = Vec3(0.025, 0.025, 0.07 - 0.0002 * (i + 1));
    last = backend->tick(request);
  }
  std::vector<Vec3> x;
  backend->positions(x);
  return x;
}

TEST(Gather, ThreadCountDoesNotChangeResults) {
  const Model model = random_model(64, 256);
  Reaction r1, r2;
  const auto x1 = pushed_run(model, {Precision::Double, 1}, r1);
  const auto x2 = pushed_run(model, {Precision::Double, 2}, r2);
  ASSERT_GT(r1.contacts, 0);
  EXPECT_EQ(r1.force, r2.force);  // bitwise: fixed-order reduction
  EXPECT_EQ(r1.contacts, r2.contacts);
  for (size_t i = 0; i < x1.size(); ++i) EXPECT_EQ(x1[i], x2[i]) << "point " << i;
}

TEST(Gather, FloatTracksDoubleReference) {
  const Model model = random_model(64, 256);
  Reaction rd, rf;
  const auto xd = pushed_run(model, {Precision::Double, 0}, rd);
  const auto xf = pushed_run(model, {Precision::Float, 0}, rf);
  double worst = 0;
  for (size_t i = 0; i < xd.size(); ++i) worst = std::max(worst, (xd[i] - xf[i]).norm());
  const double diagonal = std::sqrt(3.0) * 0.05;
  // 2000 lightly damped steps in float (epsilon 6e-8) while the tool moves:
  // rounding accumulates and is amplified by the contact; measured 3.5e-5 of
  // the diagonal (3 um on 9 cm), tolerance 1e-4 (9 um, far below any
  // deformation of interest here, ~4 mm).
  EXPECT_LT(worst, 1e-4 * diagonal);
  EXPECT_LT((rd.force - rf.force).norm(), 1e-3 * rd.force.norm());
}

}  // namespace
}  // namespace gather_test
}  // namespace organsim
