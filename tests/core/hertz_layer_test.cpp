// The sub-cell layer of a sphere's or a capsule's surface contact
// (force_law::hertz_layer_offset, line_layer_offset, HertzLayer): the laws
// themselves, their blend along a capsule, the reference's and the CPU
// backends' use of it, before and after a cut.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "core/model/contact_layer.h"
#include "core/physics/force_law.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "tests/core/contact_test_util.h"
#include "core/model/model_rebuild.h"

namespace organsim {
namespace hertz_layer_test {
namespace {

constexpr double kSize = testing::kContactBox;
constexpr double kK = testing::kContactK;

// E* 5 kPa, R 2 cm, a_h 4 mm: the liver's tool on 8 mm cells.
constexpr double kEStar = 5000, kRadius = 0.02, kPunch = 0.004;

double hertz_force(double a) { return 4 * kEStar * a * a * a / (3 * kRadius); }

// n random penalties f with stiffnesses k: normals within about 45 degrees
// of -z, forces and stiffnesses over six decades about the punch's own (2
// E* a_h), each placed along the axis within `spread` of its start (0: a
// sphere).
void add_random_penalties(force_law::HertzLayer& layer, std::mt19937& rng, int n, double spread, std::vector<Vec3>& f,
                          std::vector<double>& k) {
  std::uniform_real_distribution<double> decades(-3, 3), unit(-1, 1);
  for (int i = 0; i < n; ++i) {
    const Vec3 dir = Vec3(0.5 * unit(rng), 0.5 * unit(rng), -1).normalized();
    f.push_back(hertz_force(kPunch) * std::pow(10.0, decades(rng)) / n * dir);
    k.push_back(2 * kEStar * kPunch * std::pow(10.0, decades(rng)));
    const double along = spread > 0 ? spread * (0.5 + 0.5 * unit(rng)) : 0;
    layer.add(f.back().data(), k.back(), kPunch / force_law::kHertzLayerPunchFactor, kEStar, along);
  }
}

// offset(load) never falls as the load rises from `from` to `to` by 10 % steps.
template <class Offset>
void expect_rising(const Offset& offset, double from, double to) {
  double last = 0;
  for (double load = from; load < to; load *= 1.1) {
    const double d = offset(load);
    EXPECT_GE(d, last) << "load " << load;
    last = d;
  }
}

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
  // A sphere smaller than twice a_h (a probe): held where a reaches R / 2,
  // continuously (Hertz's paraboloid is 7 % off the sphere there).
  constexpr double kProbe = 0.006, kLimit = force_law::kLayerContactLimit * kProbe;
  const double at_limit = 4 * kEStar * kLimit * kLimit * kLimit / (3 * kProbe);
  const double held = force_law::hertz_layer_offset_at(kLimit, kProbe, kPunch);
  EXPECT_NEAR(hertz_layer_offset(at_limit * (1 - 1e-9), kEStar, kProbe, kPunch), held, 1e-8 * held);
  EXPECT_EQ(hertz_layer_offset(at_limit * 2, kEStar, kProbe, kPunch), held);
  expect_rising([](double f) { return hertz_layer_offset(f, kEStar, kRadius, kPunch); }, at / 1000, 2 * at);
}

// The line law against the half-plane it comes from: in plane strain the
// surface sinks by -(2 / (pi E*)) int p(s) ln|x - s| ds (plus a constant
// set by the body's size), so the cylinder's indentation less the strip
// punch's under the same P is that integral at x = 0 over Hertz's
// elliptical pressure less the punch's 1 / sqrt(c^2 - s^2) pressure,
// evaluated here by quadrature (s = b sin t, s = c sin t: the integrands'
// only singularity is ln|sin t|, integrable; 400k midpoints give 1e-6).
// Beyond b = c the law holds c^2 / (4 R); it is continuous there, and it
// rises with P.
TEST(HertzLayer, LineOffsetIsACylinderLessAStripPunchUpToTheCellsHalfWidthAndConstantBeyond) {
  using force_law::line_layer_offset;
  constexpr double kCapsule = 0.008, kHalfWidth = 0.003;  // c below R / 2
  EXPECT_EQ(line_layer_offset(0, kEStar, kCapsule, kHalfWidth), 0);
  EXPECT_EQ(line_layer_offset(-1, kEStar, kCapsule, kHalfWidth), 0);
  const auto half_width = [&](double P) { return std::sqrt(4 * P * kCapsule / (M_PI * kEStar)); };
  const auto log_moment = [](double width, const std::function<double(double)>& weight) {
    constexpr int n = 400000;
    double sum = 0;
    for (int i = 0; i < n; ++i) {
      const double t = -M_PI / 2 + (i + 0.5) * M_PI / n;
      sum += weight(t) * std::log(std::abs(width * std::sin(t)));
    }
    return sum * M_PI / n;
  };
  for (const double P : {0.2, 1.0, 3.0}) {  // N/m: b from 0.6 to 2.5 mm, all below c
    const double b = half_width(P);
    ASSERT_LT(b, kHalfWidth);
    // int p ln|s| ds: Hertz's p = (2P / (pi b^2)) sqrt(b^2 - s^2), ds = b cos t dt; the punch's p ds = (P / pi) dt.
    const double cylinder = log_moment(b, [&](double t) { return 2 * P / M_PI * std::cos(t) * std::cos(t); });
    const double punch = log_moment(kHalfWidth, [&](double) { return P / M_PI; });
    const double want = -2 / (M_PI * kEStar) * (cylinder - punch);
    EXPECT_NEAR(line_layer_offset(P, kEStar, kCapsule, kHalfWidth), want, 1e-5 * want) << "P " << P;
  }
  const double at = M_PI * kEStar * kHalfWidth * kHalfWidth / (4 * kCapsule);  // b = c
  const double beyond = kHalfWidth * kHalfWidth / (4 * kCapsule);
  EXPECT_NEAR(line_layer_offset(at * (1 - 1e-6), kEStar, kCapsule, kHalfWidth), beyond, 1e-9 * beyond);
  EXPECT_EQ(line_layer_offset(at * 3, kEStar, kCapsule, kHalfWidth), beyond);
  expect_rising([](double P) { return line_layer_offset(P, kEStar, kCapsule, kHalfWidth); }, at / 1000, 2 * at);
  // A shaft narrower than the cells (R / 2 < c): held where b reaches R / 2,
  // continuously.
  constexpr double kThin = 0.004, kLimit = force_law::kLayerContactLimit * kThin;
  const double at_limit = M_PI * kEStar * kLimit * kLimit / (4 * kThin);  // b = R / 2
  const double held = kLimit * kLimit / (2 * kThin) * (std::log(kHalfWidth / kLimit) + 0.5);
  EXPECT_NEAR(line_layer_offset(at_limit * (1 - 1e-9), kEStar, kThin, kHalfWidth), held, 1e-8 * held);
  EXPECT_EQ(line_layer_offset(at_limit * 2, kEStar, kThin, kHalfWidth), held);
  EXPECT_EQ(line_layer_offset(at_limit * 100, kEStar, kThin, kHalfWidth), held);
}

// Touches spread evenly along a capsule's axis: the layer reads their
// length (sqrt(12 var), the length of a uniform line load with the same
// spread: L sqrt(1 - 1/n^2) for n equal touches at spacing L / n) and
// blends the laws by beta = min(1, L / (2 a_h)): the sphere's alone with no
// spread, the line's alone (P = F / L) once L reaches 2 a_h, the weighted
// sum between. Its solve then satisfies delta = delta(G(delta)) whatever
// the blend, with penalties lifted off as for the sphere.
TEST(HertzLayer, ACapsulesLayerBlendsTheSphereAndTheLineByTheContactsLengthAlongItsAxis) {
  constexpr double kCapsule = 0.005;
  const double a_h = kPunch, raw = kPunch / force_law::kHertzLayerPunchFactor;
  const double c = force_law::kLineLayerHalfWidthFactor * raw;
  const double F = 0.3;  // N
  for (const double length : {0.0, 0.5 * a_h, 1.5 * a_h, 2 * a_h, 10 * a_h}) {
    SCOPED_TRACE("spread " + std::to_string(length) + " m");
    force_law::HertzLayer layer;
    constexpr int n = 20;
    for (int i = 0; i < n; ++i) {
      const double f[3] = {0, 0, F / n};
      layer.add(f, 2 * kEStar * kPunch, raw, kEStar, 0.01 + (i + 0.5) * length / n);
    }
    const double L = length * std::sqrt(1 - 1.0 / (n * n));
    EXPECT_NEAR(layer.contact_length(), L, 1e-9 * a_h);
    EXPECT_NEAR(layer.punch_radius(), a_h, 1e-15);
    EXPECT_NEAR(layer.line_half_width(), c, 1e-15);
    const double beta = std::min(1.0, L / (2 * a_h));
    EXPECT_NEAR(layer.line_share(), beta, 1e-9);
    const double sphere = force_law::hertz_layer_offset(F, kEStar, kCapsule, layer.punch_radius());
    const double line = L > 0 ? force_law::line_layer_offset(F / L, kEStar, kCapsule, c) : 0;
    EXPECT_NEAR(layer.offset_for(F, kCapsule), (1 - beta) * sphere + beta * line, 1e-6 * sphere);
    if (length == 0) {
      EXPECT_EQ(layer.offset_for(F, kCapsule), sphere);
    }
    if (beta == 1) {
      EXPECT_NEAR(layer.offset_for(F, kCapsule), line, 1e-15);
    }
  }
  // A probe pressed in on its end: the shaft's touches on the walls of the
  // hole push across the contact's direction and carry no length (weighed
  // by their size they would make it a line).
  {
    force_law::HertzLayer probe;
    const double tip[3] = {0, 0, 0.2}, east[3] = {0.3, 0, 0}, west[3] = {-0.3, 0, 0};
    probe.add(tip, 2 * kEStar * kPunch, raw, kEStar, 0.0);
    probe.add(east, 2 * kEStar * kPunch, raw, kEStar, 0.004);
    probe.add(west, 2 * kEStar * kPunch, raw, kEStar, 0.008);
    EXPECT_EQ(probe.contact_length(), 0);
    EXPECT_EQ(probe.line_share(), 0);
  }
  // The solve over random penalties spread along the axis by 0 to 4 a_h.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> spread(0, 4 * a_h);
  int dropped = 0, blended = 0, lines = 0;
  force_law::HertzLayer layer;
  for (int trial = 0; trial < 2000; ++trial) {
    layer.clear();
    const int n = 2 + trial % 6;
    std::vector<Vec3> f;
    std::vector<double> k;
    add_random_penalties(layer, rng, n, spread(rng), f, k);
    layer.solve(kCapsule);
    const double beta = layer.line_share();
    blended += beta > 0 && beta < 1;
    lines += beta == 1;
    Vec3 sum = Vec3::Zero(), scaled = Vec3::Zero();
    for (int i = 0; i < n; ++i) sum += f[i];
    for (int i = 0; i < n; ++i) {
      dropped += layer.factor(i) == 0;
      scaled += layer.factor(i) * f[i];
    }
    // The solve settles the force to 1e-12 of itself; behind penalties a
    // thousand times stiffer than the punch that moves delta by up to ~1e-9.
    const double G = scaled.dot(sum.normalized());
    EXPECT_NEAR(layer.offset(), layer.offset_for(G, kCapsule), 1e-7 * layer.offset()) << "trial " << trial;
  }
  EXPECT_GT(blended, 100);
  EXPECT_GT(lines, 100);
  EXPECT_GT(dropped, 10);
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
  int below = 0, beyond = 0, dropped = 0;
  force_law::HertzLayer layer;
  for (int trial = 0; trial < 2000; ++trial) {
    layer.clear();
    const int n = 1 + trial % 6;
    std::vector<Vec3> f;
    std::vector<double> k;
    add_random_penalties(layer, rng, n, 0, f, k);
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

// The sphere, and a capsule (radius 1 cm) lying along x over the top, as
// deep at its middle: its line layer (its contact is longer than the
// cells' punch diameter). Tilted by 2 degrees: along a face parallel to its
// axis the closest points tie, and float and double break the ties apart.
const ToolPlacement kSphere{kCenter, kCenter, kCenter, kToolRadius};
const ToolPlacement kCapsule{kCenter, kCenter - Vec3(0.012, 0, 0.0004), kCenter + Vec3(0.012, 0, 0.0004),
                             kToolRadius};

// The reference lowers every touching triangle's penalty by its layer
// factor: the reaction is still minus what the tissue receives, the total
// falls, and each triangle's share comes from the same HertzLayer, solved
// here independently of the reference over the same penalties.
TEST(HertzLayer, TheReferenceAppliesTheLayersFactorToEveryPenalty) {
  const Model m = box();
  const ContactLayer layer = contact_layer(m);
  for (const ToolPlacement* tool : {&kSphere, &kCapsule}) {
    SCOPED_TRACE(tool == &kSphere ? "sphere" : "capsule");
    std::vector<Vec3> plain(m.npoint(), Vec3::Zero()), layered(m.npoint(), Vec3::Zero());
    const Reaction without = reference_surface_forces(m, m.rest_position, *tool, kK, plain);
    const Reaction with = reference_surface_forces(m, m.rest_position, *tool, kK, layered, &layer);
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
      const Vec3 &x0 = m.rest_position[t[0]], &x1 = m.rest_position[t[1]], &x2 = m.rest_position[t[2]];
      Vec3 f;
      if (!force_law::capsule_triangle_penalty(tool->a, tool->b, kToolRadius, x0, x1, x2, kK, share, f, w)) continue;
      const TriangleLayer tl = triangle_layer(layer, t);
      h.add(f.data(), kK * force_law::triangle_penalty_scale(share), tl.punch_radius, tl.e_star,
            force_law::segment_axial_position(Vec3(w[0] * x0 + w[1] * x1 + w[2] * x2), tool->a, tool->b));
      touches.push_back({&t, f});
    }
    h.solve(kToolRadius);
    EXPECT_EQ(h.line_share(), tool == &kSphere ? 0 : 1);
    Vec3 want = Vec3::Zero();
    for (size_t i = 0; i < touches.size(); ++i) want -= h.factor(i) * touches[i].second;
    EXPECT_LT((with.force - want).norm(), 1e-12 * want.norm());
  }
}

// One substep from rest with the sphere pressed in: every CPU kernel and
// precision applies the reference's layered forces (recovered from the
// points' motion) and reports minus their sum; the same after a cut
// through the contact, whose new faces the layer's punch radii follow.
TEST(HertzLayer, CpuBackendsApplyTheReferencesLayeredForcesBeforeAndAfterACut) {
  const Model whole = box();
  const Model cut = rebuild_model(whole, testing::split_across_plane_x(whole, 0.5 * kSize));
  const double dt = 1e-4;
  for (const ToolPlacement* placed : {&kSphere, &kCapsule}) {
    for (const Model* m : {&whole, &cut}) {
      BackendTool tool{true, ToolMode::Push, kToolRadius, kK, ToolContact::Surface};
      tool.hertz_layer = true;
      if (placed == &kCapsule) {
        tool.shape = ToolShape::Capsule;
        tool.end_a = placed->a - kCenter, tool.end_b = placed->b - kCenter;
      }
      const ContactLayer layer = contact_layer(*m);
      testing::Contact want;
      want.force.assign(m->npoint(), Vec3::Zero());
      want.reaction = reference_surface_forces(*m, m->rest_position, *placed, kK, want.force, &layer);
      for (const Precision precision : {Precision::Double, Precision::Float}) {
        auto backend = make_cpu_backend(*m, tool, {precision, 1});
        SCOPED_TRACE(backend->device() + (placed == &kSphere ? ", sphere" : ", capsule") +
                     (m == &cut ? ", after the cut" : ""));
        const double tolerance = precision == Precision::Double ? 1e-8 : 1e-4;  // float: 24-bit positions
        const Reaction got = backend->tick(testing::one_step_at(dt, kCenter));
        const testing::Applied applied = testing::applied_in_one_step(*m, *backend, dt, want.force);
        ASSERT_GT(applied.peak, 0.01);
        EXPECT_LT(applied.worst, tolerance * applied.peak);
        EXPECT_LT((got.force - want.reaction.force).norm(), tolerance * want.reaction.force.norm());
        const Plan plan = backend->plan();  // by value: begin and end from the same copy
        EXPECT_TRUE(std::any_of(plan.passes.begin(), plan.passes.end(), [](const PassInfo& p) {
          return p.detail.find("sub-cell layer") != std::string::npos;
        }));
      }
    }
  }
}

}  // namespace
}  // namespace hertz_layer_test
}  // namespace organsim
