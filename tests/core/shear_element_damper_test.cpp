// The shear element's damper (Kelvin-Voigt, viscous stress 2 mu_e tau D with
// D = sym(Fdot F^-1); core/model/shear_element.h, docs/physics.md): on one
// tet it is tau times the element's stiffness at small strain, zero under
// rigid motion of a strained tet, and dissipative for any deformation; a
// nu-0 block stops ringing with it; the reference backend, the kernel and
// the scatter step match the reference force with it; and dt_crit includes it.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/model/shear_element.h"
#include "core/model/stiffness.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_backend.h"
#include "core/sim/reference_forces.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"
#include "tests/core/force_law_checks.h"
#include "tests/core/stability_test_util.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace shear_element_damper_test {
namespace {

constexpr double kTau = 0.01;  // s, the damping time of these tests

// One irregular free tet (edges ~1 cm), E = 4 kPa at nu = 0: the shear
// element is its whole stiffness (the springs have none), damped with tau.
Model single_tet(double tau = kTau) {
  TetMesh mesh;
  mesh.points = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0.002, 0.011, 0), Vec3(0.003, 0.002, 0.009)};
  mesh.tets = {{0, 1, 2, 3}};
  Material m = testing::soft_material(0.0);
  m.spring_damping_time = tau;
  return build_model(mesh, m, {});
}

// The damper's force alone: the reference force at (x, v) minus at (x, 0).
std::vector<Vec3> damping_force(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& v) {
  std::vector<Vec3> with, without, zero(x.size(), Vec3::Zero());
  reference_internal_forces(model, x, v, with);
  reference_internal_forces(model, x, zero, without);
  for (size_t i = 0; i < x.size(); ++i) with[i] -= without[i];
  return with;
}

double largest_norm(const std::vector<Vec3>& v) {
  double s = 0;
  for (const Vec3& f : v) s = std::max(s, f.norm());
  return s;
}

std::vector<Vec3> random_vectors(size_t n, double scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, scale);
  std::vector<Vec3> v(n);
  for (Vec3& p : v) p = Vec3(noise(rng), noise(rng), noise(rng));
  return v;
}

// -tau K v with K = -df/dx of the elastic force at x by central differences
// (h = 1e-8 m on a 1 cm tet).
std::vector<Vec3> tau_stiffness_times(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& v) {
  const double h = 1e-8;
  std::vector<Vec3> out(x.size(), Vec3::Zero()), plus, minus, zero(x.size(), Vec3::Zero());
  for (size_t j = 0; j < x.size(); ++j) {
    for (int k = 0; k < 3; ++k) {
      std::vector<Vec3> xp = x, xm = x;
      xp[j][k] += h;
      xm[j][k] -= h;
      reference_internal_forces(model, xp, zero, plus);
      reference_internal_forces(model, xm, zero, minus);
      // Column (j, k) of -K is (f(x + h) - f(x - h)) / 2h; -tau K v adds it times tau v_jk.
      for (size_t i = 0; i < x.size(); ++i) out[i] += model.shear_damping_time * v[j][k] * (plus[i] - minus[i]) / (2 * h);
    }
  }
  return out;
}

// At rest the damper is exactly -tau K v, as a spring's damper is tau times
// its stiffness along its axis. Central differences with h = 1e-8 m on a
// 1 cm tet: truncation ~(h / 1 cm)^2 = 1e-12 relative (the force is
// smooth), rounding ~1e-16 |f| L / h; tolerance 1e-6 of the force. At a
// random strain of ~1e-4 the two differ at first order in the strain (cof F,
// J and K's own dependence on F): tolerance 2e-3.
TEST(ShearElementDamper, IsTauTimesTheStiffnessAtSmallStrain) {
  const Model model = single_tet();
  ASSERT_TRUE(model.has_shear_element());
  EXPECT_EQ(model.shear_damping_time, kTau);
  for (double strain : {0.0, 1e-4}) {
    std::vector<Vec3> x = model.rest_position;
    if (strain > 0) {
      const std::vector<Vec3> noise = random_vectors(x.size(), strain * 0.01, 11);
      for (size_t i = 0; i < x.size(); ++i) x[i] += noise[i];
    }
    for (unsigned seed : {1u, 2u, 3u}) {
      const std::vector<Vec3> v = random_vectors(x.size(), 0.05, seed);
      const std::vector<Vec3> got = damping_force(model, x, v), want = tau_stiffness_times(model, x, v);
      const double scale = largest_norm(want);
      ASSERT_GT(scale, 0);
      for (size_t i = 0; i < x.size(); ++i)
        EXPECT_LT((got[i] - want[i]).norm(), (strain == 0 ? 1e-6 : 2e-3) * scale)
            << "strain " << strain << " seed " << seed << " point " << i;
    }
  }
}

// A strained tet (stretched, sheared, J = 1.17) rigidly rotated by several
// angles and moving rigidly (spin and translation) has no damping force:
// Fdot cof^T = J W is skew. The scale is the damping force of a random
// velocity of the same size; rounding leaves ~1e-15 of it (tolerance
// 1e-12). A damper on sym(Fdot) instead of D fails this at every angle.
TEST(ShearElementDamper, RigidMotionOfAStrainedTetHasNoForce) {
  const Model model = single_tet();
  Eigen::Matrix3d F0;
  F0 << 1.2, 0.1, 0, 0, 0.9, 0.05, 0.02, 0, 1.1;
  const Vec3 axis = Vec3(1, 2, 3).normalized(), spin(0.3, -5, 2), shift(0.4, -0.2, 0.1);
  for (double degrees : {0.0, 30.0, 90.0, 179.0}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(degrees * M_PI / 180, axis).toRotationMatrix();
    std::vector<Vec3> x(4), rigid(4), translation(4, shift);  // spin about x_0, and a translation
    for (int i = 0; i < 4; ++i) x[i] = R * F0 * model.rest_position[i] + Vec3(0.05, 0.01, -0.02);
    for (int i = 0; i < 4; ++i) rigid[i] = spin.cross(x[i] - x[0]);
    const double speed = largest_norm(rigid);
    const double scale = largest_norm(damping_force(model, x, random_vectors(4, speed, 5)));
    ASSERT_GT(scale, 0);
    EXPECT_LT(largest_norm(damping_force(model, x, rigid)), 1e-12 * scale) << degrees << " degrees, spin";
    EXPECT_LT(largest_norm(damping_force(model, x, translation)), 1e-12 * scale) << degrees << " degrees, translation";
  }
}

// Its power sum_i f_i . v_i is -2 tau k_t J_d |D_d|^2 <= 0 (D_d =
// sym(Fdot cof^T) / J_d, J_d = max(J, J_min)) for any deformation: 300
// random F, from stretched to crushed below J_min and inverted (J < 0), and
// random velocities. Equality to 1e-9 relative (double rounding of a few
// 3x3 products).
TEST(ShearElementDamper, DissipatesForEveryDeformationAndVelocity) {
  const Model model = single_tet();
  const double kt = model.tet_shear_k[0];
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  int crushed = 0, inverted = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Eigen::Matrix3d F;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) F(r, c) = (r == c ? 1.0 : 0.0) + 0.7 * u(rng);
    std::vector<Vec3> x(4);
    for (int i = 0; i < 4; ++i) x[i] = F * model.rest_position[i];
    const std::vector<Vec3> v = random_vectors(4, 0.1, 100 + trial);
    const std::vector<Vec3> f = damping_force(model, x, v);
    double power = 0;
    for (int i = 0; i < 4; ++i) power += f[i].dot(v[i]);
    const Eigen::Matrix3d Fdot = deformation_gradient(model, 0, v);
    const double J = F.determinant(), jd = std::max(J, force_law::kShearElementMinJ);
    const Eigen::Matrix3d A = Fdot * (J * F.inverse().transpose()).transpose();
    const Eigen::Matrix3d Dd = (A + A.transpose()) / (2 * jd);
    const double expected = -2 * kTau * kt * jd * Dd.squaredNorm();
    EXPECT_LT(power, 0) << "trial " << trial << " J " << J;
    EXPECT_NEAR(power, expected, 1e-9 * std::abs(expected)) << "trial " << trial << " J " << J;
    crushed += J < force_law::kShearElementMinJ;
    inverted += J < 0;
  }
  // The draws reach both the barrier's extension and inverted tets.
  EXPECT_GT(crushed, 20);
  EXPECT_GT(inverted, 10);
}

// Total energy of a backend's state: elastic at x_n plus kinetic from the
// centred velocity (x_{n+1} - x_{n-1}) / 2 dt, after `steps` steps from rest.
double energy_after(Backend& backend, const Model& model, int steps, double dt) {
  std::vector<Vec3> before, now, after;
  testing::run_ticks(backend, steps - 1, dt, 1);
  backend.positions(before);
  testing::run_ticks(backend, 1, dt, 1);
  backend.positions(now);
  testing::run_ticks(backend, 1, dt, 1);
  backend.positions(after);
  double kinetic = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) kinetic += 0.5 * model.mass[i] * ((after[i] - before[i]) / (2 * dt)).squaredNorm();
  return elastic_energy(model, now) + kinetic;
}

// The ringing of issue 12: a nu-0 block (all of its stiffness in the shear
// element, no spring dampers, no drag) released from a 2 % stretch. Without
// the element's damper nothing dissipates: after 0.3 s (about 3 periods of
// its lowest mode) position Verlet at dt = 1e-4 s (omega_max dt ~ 0.1) keeps
// the energy to within (omega dt)^2 / 4 of the start (measured 2e-5),
// tolerance 1e-3. With
// tau = 10 ms the lowest mode alone decays as exp(-tau omega_1^2 t) ~ e^-10:
// below 1 % of the start.
TEST(ShearElementDamper, StopsTheRingingOfANuZeroBlock) {
  const double dt = 1e-4;
  const int steps = 3000;
  double remaining[2];
  for (int damped = 0; damped < 2; ++damped) {
    Material m = testing::soft_material(0.0);
    m.spring_damping_time = damped ? kTau : 0;
    m.viscous_damping = 0;
    const Model model = build_model(testing::jittered_box(4, 0.05, 0.25, 3), m, testing::fixed_bottom_options());
    ASSERT_LT(dt, 0.5 * estimate_critical_step(model).dt_crit);
    std::vector<Vec3> stretched = model.rest_position;
    for (Vec3& p : stretched) p.z() *= 1.02;
    const double start = elastic_energy(model, stretched);
    auto backend = make_reference_backend(model, {}, Integrator::Verlet);
    backend->set_state(stretched, stretched);
    remaining[damped] = energy_after(*backend, model, steps, dt) / start;
  }
  std::cout << "energy left after 0.3 s: " << remaining[0] << " without the damper, " << remaining[1] << " with it\n";
  EXPECT_NEAR(remaining[0], 1.0, 1e-3);
  EXPECT_LT(remaining[1], 1e-2);
}

// The reference backend's step, the kernel's (double and float) and the
// scatter step against Verlet on the reference force with the damper carrying most of the force: a moving state
// (velocities ~0.2 m/s, 1 mm displacements) and the same velocities on a
// block crushed to 0.3 of its height (J < J_min: the clamped 1 / J_d). The
// damper's share of the force is checked first, so the comparison is about
// it; tolerances as in force_law_checks.h.
TEST(ShearElementDamper, StepsAndScatterStepMatchTheReferenceForce) {
  for (ShearFormulation formulation : {ShearFormulation::Smoothed, ShearFormulation::PerTet}) {
    SCOPED_TRACE(shear_formulation_name(formulation));
    const double dt = 1e-4;
    Material m = testing::soft_material(0.0);
    m.spring_damping_time = kTau;
    m.shear_formulation = formulation;
    const Model model = build_model(testing::jittered_box(4, 0.05, 0.25, 4), m, testing::fixed_bottom_options());
    std::vector<Vec3> x, x_prev;
    testing::random_state(model, 3, dt, x, x_prev);
    std::vector<Vec3> crushed = model.rest_position, crushed_prev(x.size());
    for (Vec3& p : crushed) p.z() *= 0.3;
    for (size_t i = 0; i < x.size(); ++i) crushed_prev[i] = crushed[i] - (x[i] - x_prev[i]);
    for (const auto& [now, prev] : {std::pair{x, x_prev}, std::pair{crushed, crushed_prev}}) {
      std::vector<Vec3> v(now.size()), total;
      for (size_t i = 0; i < now.size(); ++i) v[i] = (now[i] - prev[i]) / dt;
      reference_internal_forces(model, now, v, total);
      std::cout << "damper share " << largest_norm(damping_force(model, now, v)) / largest_norm(total) << "\n";
      EXPECT_GT(largest_norm(damping_force(model, now, v)), 0.5 * largest_norm(total));
      const testing::StepError r = testing::reference_step_error(model, now, prev, dt);
      EXPECT_LT(r.worst, 1e-15 + 1e-12 * r.largest) << "reference";
      for (Precision precision : {Precision::Double, Precision::Float}) {
        const testing::StepError e = testing::kernel_step_error(model, now, prev, dt, precision);
        const bool dbl = precision == Precision::Double;
        EXPECT_LT(e.worst, dbl ? 1e-15 + 1e-12 * e.largest : 1e-8 + 1e-4 * e.largest) << (dbl ? "double" : "float");
      }
    }
    // From rest under gravity the sag's velocities load the damper: 200 steps
    // of both in double agree to rounding.
    const Model gravity_model = build_model(testing::jittered_box(4, 0.05, 0.25, 4), m, testing::fixed_bottom_options(Vec3(0, 0, -9.81)));
    const testing::PathDifference d = testing::scatter_against_reference(gravity_model, 200, dt);
    ASSERT_GT(d.motion, 1e-6);
    EXPECT_LT(d.worst, 1e-9 * d.motion);
  }
}

// dt_crit with the damper: below nu = 1/4 the springs and the per-tet
// element share one damping time, so every mode is damped at tau omega^2;
// with tau = 1 / omega_max the top mode's damping ratio is 1/2 and the step
// shrinks to (sqrt(5) - 1) / 2 of the undamped one. Smoothed, the damper
// stays tau times the per-tet element's stiffness while the elastic part is
// the softer blend (the node average of k_t (F_t - I) stores no more than
// the tets it averages), so the top mode is damped more: ratio above 1/2,
// step below (sqrt(5) - 1) / 2 of the undamped one. The integrator agrees
// in both: stable 2 % below, unstable 2 % above (without the element's
// damper in the estimate dt_crit would be 1.6 times too long at nu = 0, and
// the step at 0.98 of it would blow up). The guaranteed (Gershgorin) step
// stays below it.
TEST(ShearElementDamper, CriticalStepIncludesTheDamper) {
  for (ShearFormulation formulation : {ShearFormulation::PerTet, ShearFormulation::Smoothed}) {
    for (double nu : {0.0, 0.15}) {
      SCOPED_TRACE(shear_formulation_name(formulation));
      const bool per_tet = formulation == ShearFormulation::PerTet;
      Material m = testing::undamped_material(3000);
      m.poisson_ratio = nu;
      m.shear_formulation = formulation;
      const StabilityReport undamped = estimate_critical_step(testing::stability_box(3, 0.03, m, 0.2, 5));
      m.spring_damping_time = 1 / undamped.omega_max;
      const Model model = testing::stability_box(3, 0.03, m, 0.2, 5);
      const StabilityReport r = estimate_critical_step(model);
      EXPECT_TRUE(r.converged) << nu;
      const double golden = (std::sqrt(5.0) - 1) / 2;
      if (per_tet) {
        EXPECT_NEAR(r.damping_ratio, 0.5, 1e-6) << nu;
        EXPECT_NEAR(r.dt_crit / r.dt_crit_undamped, golden, 1e-6) << nu;
      } else {
        EXPECT_GT(r.damping_ratio, 0.5) << nu;
        EXPECT_LT(r.dt_crit / r.dt_crit_undamped, golden) << nu;
      }
      EXPECT_LE(r.dt_crit_gershgorin, r.dt_crit) << nu;
      EXPECT_FALSE(testing::perturbation_grows(model, 0.98 * r.dt_crit)) << nu;
      EXPECT_TRUE(testing::perturbation_grows(model, 1.02 * r.dt_crit)) << nu;
    }
  }
}

}  // namespace
}  // namespace shear_element_damper_test
}  // namespace organsim
