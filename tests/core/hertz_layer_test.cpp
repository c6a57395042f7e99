// The sub-cell Hertz layer of a sphere's surface contact
// (force_law::hertz_layer_offset, HertzLayer): the law itself, the
// reference's and the CPU backends' use of it, before and after a cut.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/model/contact_layer.h"
#include "core/physics/force_law.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "tests/core/contact_test_util.h"
#include "core/model/model_rebuild.h"

namespace organsim {
namespace {

constexpr double kSize = testing::kContactBox;
constexpr double kK = testing::kContactK;

// E* 5 kPa, R 2 cm, a_h 4 mm: the liver's tool on 8 mm cells.
constexpr double kEStar = 5000, kRadius = 0.02, kPunch = 0.004;

double hertz_force(double a) { return 4 * kEStar * a * a * a / (3 * kRadius); }

// delta(F) is Hertz's indentation a^2 / R less the punch's F / (2 E* a_h)
// below a_h (so nearly all of Hertz's at small F, where the punch's is of
// higher order), continuous with a zero slope where a reaches a_h, and
// constant beyond. A layer that kept rising past a_h would soften contacts
// the cells already resolve.
TEST(HertzLayer, OffsetIsHertzLessAPunchUpToTheCellsRadiusAndConstantBeyond) {
  using force_law::hertz_layer_offset;
  EXPECT_EQ(hertz_layer_offset(0, kEStar, kRadius, kPunch), 0);
  EXPECT_EQ(hertz_layer_offset(-1, kEStar, kRadius, kPunch), 0);
  const double a = 0.25 * kPunch, F = hertz_force(a);
  EXPECT_NEAR(hertz_layer_offset(F, kEStar, kRadius, kPunch), a * a / kRadius - F / (2 * kEStar * kPunch),
              1e-12 * a * a / kRadius);
  const double at = hertz_force(kPunch), beyond = kPunch * kPunch / (3 * kRadius);
  EXPECT_NEAR(hertz_layer_offset(at * (1 - 1e-6), kEStar, kRadius, kPunch), beyond, 1e-9 * beyond);
  EXPECT_EQ(hertz_layer_offset(at * 1.5, kEStar, kRadius, kPunch), beyond);
  EXPECT_EQ(hertz_layer_offset(at * 100, kEStar, kRadius, kPunch), beyond);
  double last = 0;
  for (double f = at / 1000; f < 2 * at; f *= 1.1) {
    const double d = hertz_layer_offset(f, kEStar, kRadius, kPunch);
    EXPECT_GE(d, last) << "F " << f;
    last = d;
  }
}

// HertzLayer::solve finds the offset delta with F(delta) = G(delta): the
// layer's force (the Hertz force at the radius whose delta it is) equals
// the penalties' force along their sum with the sphere moved back by delta,
// each penalty lowered by k_t c_t delta and never below zero. Random sets of
// 1 to 6 penalties, with stiffnesses from a thousandth to a thousand times
// the punch's own 2 E* a_h and forces on both sides of a_h; one penalty
// under a very stiff spring leaves the layer alone to carry the depth.
double layer_force(const force_law::HertzLayer& layer) {
  const double d = layer.offset(), a_h = layer.punch_radius(), e = layer.e_star();
  if (d >= a_h * a_h / (3 * kRadius) * (1 - 1e-12)) return -1;  // beyond a_h: F is G itself
  // delta(a) = a^2 / R - 2 a^3 / (3 R a_h) rises on [0, a_h]: invert by bisection.
  double lo = 0, hi = a_h;
  for (int i = 0; i < 200; ++i) {
    const double a = 0.5 * (lo + hi);
    (a * a / kRadius - 2 * a * a * a / (3 * kRadius * a_h) < d ? lo : hi) = a;
  }
  const double a = 0.5 * (lo + hi);
  return 4 * e * a * a * a / (3 * kRadius);
}

TEST(HertzLayer, ItsForceEqualsThePenaltiesWithTheSphereMovedBackByItsOffset) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> decades(-3, 3), unit(-1, 1);
  int below = 0, beyond = 0, dropped = 0;
  force_law::HertzLayer layer;
  for (int trial = 0; trial < 2000; ++trial) {
    layer.clear();
    const int n = 1 + trial % 6;
    std::vector<Vec3> f;
    std::vector<double> k;
    for (int i = 0; i < n; ++i) {
      // Normals within about 45 degrees of -z, forces spread over decades.
      const Vec3 dir = Vec3(0.5 * unit(rng), 0.5 * unit(rng), -1).normalized();
      f.push_back(hertz_force(kPunch) * std::pow(10.0, decades(rng)) / n * dir);
      k.push_back(2 * kEStar * kPunch * std::pow(10.0, decades(rng)));
      layer.add(f.back().data(), k.back(), kPunch / force_law::kHertzLayerPunchFactor, kEStar);
    }
    layer.solve(kRadius);
    Vec3 sum = Vec3::Zero(), scaled = Vec3::Zero();
    for (int i = 0; i < n; ++i) sum += f[i];
    const Vec3 along = sum.normalized();
    for (int i = 0; i < n; ++i) {
      const double c = f[i].normalized().dot(along);
      const double want = std::max(0.0, f[i].norm() - k[i] * c * layer.offset()) / f[i].norm();
      EXPECT_NEAR(layer.factor(i), want, 1e-12);
      ASSERT_GE(layer.factor(i), 0);
      ASSERT_LE(layer.factor(i), 1 + 1e-12);
      dropped += layer.factor(i) == 0;
      scaled += layer.factor(i) * f[i];
    }
    const double F = layer_force(layer);
    if (F < 0) {
      ++beyond;
      continue;
    }
    ++below;
    EXPECT_NEAR(F, scaled.dot(along), 1e-9 * sum.norm()) << "trial " << trial;
  }
  EXPECT_GT(below, 100);
  EXPECT_GT(beyond, 100);
  EXPECT_GT(dropped, 10);  // penalties lifted off entirely: the clamp at zero was exercised
  // One penalty behind a very stiff spring, a quarter of the way to a_h:
  // the sphere moves back by almost all of the depth.
  layer.clear();
  const double depth = 0.3 * kPunch * kPunch / kRadius, K = 1e9;
  const double f[3] = {0, 0, K * depth};
  layer.add(f, K, kPunch / force_law::kHertzLayerPunchFactor, kEStar);
  layer.solve(kRadius);
  EXPECT_NEAR(layer.offset(), depth, 1e-6 * depth);
}

// A sphere on a jittered box of 1 cm cells, resting 1.5 mm deep.
Model box() { return testing::contact_box(4); }
const Vec3 kCenter(0.52 * kSize, 0.47 * kSize, kSize + 0.01 - 0.0015);
constexpr double kToolRadius = 0.01;

// The reference lowers every touching triangle's penalty by its layer
// factor: the reaction is still minus what the tissue receives, the total
// falls, and each triangle's share comes from the same HertzLayer, solved
// here independently of the reference over the same penalties.
TEST(HertzLayer, TheReferenceAppliesTheLayersFactorToEveryPenalty) {
  const Model m = box();
  const ContactLayer layer = contact_layer(m);
  std::vector<Vec3> plain(m.npoint(), Vec3::Zero()), layered(m.npoint(), Vec3::Zero());
  const Reaction without = reference_surface_forces(m, m.rest_position, kCenter, kToolRadius, kK, plain);
  const Reaction with = reference_surface_forces(m, m.rest_position, kCenter, kToolRadius, kK, layered, &layer);
  ASSERT_GT(without.force.norm(), 0.1 * kK * 0.0015);
  EXPECT_GT(with.force.norm(), 0.05 * without.force.norm());
  EXPECT_LT(with.force.norm(), 0.95 * without.force.norm());
  Vec3 sum = Vec3::Zero();
  for (int32_t p = 0; p < m.npoint(); ++p) sum += layered[p];
  EXPECT_LT((with.force + sum).norm(), 1e-12 * sum.norm());
  EXPECT_EQ(with.contacts, without.contacts);
  force_law::HertzLayer h;
  std::vector<std::pair<const Tri*, Vec3>> touches;
  for (const Tri& t : m.surface) {
    double share[3], w[3];
    for (int i = 0; i < 3; ++i) share[i] = m.tool_scale(t[i]) / m.surface_count(t[i]);
    Vec3 f;
    if (!force_law::sphere_triangle_penalty(kCenter, kToolRadius, m.rest_position[t[0]], m.rest_position[t[1]],
                                            m.rest_position[t[2]], kK, share, f, w))
      continue;
    const TriangleLayer tl = triangle_layer(layer, t);
    h.add(f.data(), kK * force_law::triangle_penalty_scale(share), tl.punch_radius, tl.e_star);
    touches.push_back({&t, f});
  }
  h.solve(kToolRadius);
  Vec3 want = Vec3::Zero();
  for (size_t i = 0; i < touches.size(); ++i) want -= h.factor(i) * touches[i].second;
  EXPECT_LT((with.force - want).norm(), 1e-12 * want.norm());
}

// One substep from rest with the sphere pressed in: every CPU kernel and
// precision applies the reference's layered forces (recovered from the
// points' motion) and reports minus their sum; the same after a cut
// through the contact, whose new faces the layer's punch radii follow.
TEST(HertzLayer, CpuBackendsApplyTheReferencesLayeredForcesBeforeAndAfterACut) {
  const Model whole = box();
  const Model cut = rebuild_model(whole, testing::split_across_plane_x(whole, 0.5 * kSize));
  BackendTool tool{true, ToolMode::Push, kToolRadius, kK, ToolContact::Surface};
  tool.hertz_layer = true;
  const double dt = 1e-4;
  for (const Model* m : {&whole, &cut}) {
    const ContactLayer layer = contact_layer(*m);
    testing::Contact want;
    want.force.assign(m->npoint(), Vec3::Zero());
    want.reaction = reference_surface_forces(*m, m->rest_position, kCenter, kToolRadius, kK, want.force, &layer);
    for (const Precision precision : {Precision::Double, Precision::Float})
      for (const CpuKernel kernel : {CpuKernel::Generic, CpuKernel::Auto}) {
        auto backend = make_cpu_backend(*m, tool, {precision, 1, kernel});
        SCOPED_TRACE(backend->device() + (m == &cut ? ", after the cut" : ""));
        const double tolerance = precision == Precision::Double ? 1e-8 : 1e-4;  // float: 24-bit positions
        const Reaction got = backend->tick(testing::one_step_at(dt, kCenter));
        const testing::Applied applied = testing::applied_in_one_step(*m, *backend, dt, want.force);
        ASSERT_GT(applied.peak, 0.01);
        EXPECT_LT(applied.worst, tolerance * applied.peak);
        EXPECT_LT((got.force - want.reaction.force).norm(), tolerance * want.reaction.force.norm());
        EXPECT_NE(backend->plan().passes.end(),
                  std::find_if(backend->plan().passes.begin(), backend->plan().passes.end(), [](const PassInfo& p) {
                    return p.detail.find("Hertz layer") != std::string::npos;
                  }));
      }
  }
}

}  // namespace
}  // namespace organsim
