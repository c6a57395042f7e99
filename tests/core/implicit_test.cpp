// Implicit Euler (core/sim/reference_backend.h, implicit_system.h,
// conjugate_gradient.h): its tangent against finite differences of the
// reference forces, one step against a dense direct solve of the same
// system, the single spring's amplification against its closed form,
// Newton's quadratic convergence, a stiff model stepped far beyond dt_crit
// settling to the static solution, and a solve that cannot converge
// counted.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <utility>

#include "core/run/integrator_report.h"
#include "core/sim/reference_backend.h"
#include "core/sim/implicit_system.h"
#include "core/sim/reference_forces.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"
#include "core/util/error.h"
#include "core/validation/static_solve.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace implicit_test {
namespace {

Eigen::VectorXd flat(const std::vector<Vec3>& v) {
  Eigen::VectorXd out(3 * static_cast<Eigen::Index>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) out.segment<3>(3 * static_cast<Eigen::Index>(i)) = v[i];
  return out;
}

Material soft_material(double poisson_ratio, double damping_time) {
  Material material;
  material.density = 1000;
  material.young_modulus = 5000;
  material.poisson_ratio = poisson_ratio;
  material.spring_damping_time = damping_time;
  material.viscous_damping = 0;
  return material;
}

// A 4 cm box, base held, every free point moved by up to `amplitude` (m)
// away from rest, with random velocities up to 0.1 m/s.
struct DeformedBox {
  Model model;
  std::vector<Vec3> x, v;
};
DeformedBox deformed_box(const Material& material, double amplitude, unsigned seed) {
  DeformedBox b{build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 3, 3, 3), material,
                            testing::fixed_bottom_options()),
                {},
                {}};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  b.x = b.model.rest_position;
  b.v.assign(b.model.npoint(), Vec3::Zero());
  for (int32_t i = 0; i < b.model.npoint(); ++i) {
    if (b.model.fixed[i]) continue;
    b.x[i] += amplitude * Vec3(u(rng), u(rng), u(rng));
    b.v[i] = 0.1 * Vec3(u(rng), u(rng), u(rng));
  }
  return b;
}

// A uniform stretch by (1 + s) in every direction from the base: every spring
// in tension, so the spring tangent (k - t) u u^T + t I is exact.
DeformedBox stretched_box(const Material& material, double s) {
  DeformedBox b = deformed_box(material, 0, 1);
  for (int32_t i = 0; i < b.model.npoint(); ++i) b.x[i] = (1 + s) * b.model.rest_position[i];
  return b;
}

// -df/dx p and -df/dv p by central differences of the reference forces.
Eigen::VectorXd force_difference(const Model& m, const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                                 const Eigen::VectorXd& p, bool in_velocity, double eps) {
  std::vector<Vec3> xp = x, xm = x, vp = v, vm = v, fp, fm;
  for (int32_t i = 0; i < m.npoint(); ++i) {
    const Vec3 d = eps * p.segment<3>(3 * i);
    (in_velocity ? vp : xp)[i] += d;
    (in_velocity ? vm : xm)[i] -= d;
  }
  reference_internal_forces(m, xp, vp, fp);
  reference_internal_forces(m, xm, vm, fm);
  return -(flat(fp) - flat(fm)) / (2 * eps);
}

// Where the tangent is exact (b.v zero): K p and D p against differences
// of the reference forces for a random p, and a product with both
// coefficients against the sum of the two (the shear element's rows are
// one matrix beta K + alpha D formed per coefficient pair).
void expect_exact_tangent(const DeformedBox& b, unsigned seed) {
  ImplicitSystem system(b.model);
  system.linearise(b.x, b.v, 0, {});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd p(3 * b.model.npoint());
  for (auto& c : p) c = u(rng);
  Eigen::VectorXd kp, dp, both;
  system.apply(0, 0, 1, p, kp);
  system.apply(0, 1, 0, p, dp);
  system.apply(0, 2, 3, p, both);
  // 1e-6 relative: central differences with eps 1e-7 m against 4e-3 m
  // springs leave ~1e-9 truncation and ~1e-8 rounding; the combined
  // product is the same sums in another order (1e-12).
  const Eigen::VectorXd kfd = force_difference(b.model, b.x, b.v, p, false, 1e-7);
  const Eigen::VectorXd dfd = force_difference(b.model, b.x, b.v, p, true, 1e-5);
  EXPECT_LT((kp - kfd).norm(), 1e-6 * kfd.norm());
  EXPECT_LT((dp - dfd).norm(), 1e-6 * dfd.norm());
  EXPECT_LT((both - (2 * dp + 3 * kp)).norm(), 1e-12 * both.norm());
}

// With every spring stretched, at rest in velocity, and no volume term, K is
// the exact tangent of the spring forces, and D of the dampers (their force
// is linear in v). (With the ends moving, the damper's tension also turns
// with u: a non-symmetric term the system leaves out.)
TEST(ImplicitSystem, SpringTangentAndDamperMatchFiniteDifferencesWhereTheyAreExact) {
  DeformedBox b = stretched_box(soft_material(0.25, 0.01), 0.02);
  ASSERT_FALSE(b.model.has_volume());
  ASSERT_FALSE(b.model.has_shear_element());
  b.v.assign(b.model.npoint(), Vec3::Zero());
  expect_exact_tangent(b, 7);
}

// At rest every term's tangent is exact, the shear element's and its
// damper's included (nu < 1/4 brings the element; its stiffness blends in
// the smoothed part, its damper is shear_damping_time times the per-tet
// element's alone): K and D match differences of the reference forces in
// position and velocity.
TEST(ImplicitSystem, AtRestStiffnessAndDamperMatchFiniteDifferencesWithTheShearElement) {
  DeformedBox b = deformed_box(soft_material(0.2, 0.01), 0, 3);
  ASSERT_TRUE(b.model.has_shear_element());
  ASSERT_GT(b.model.shear_damping_time, 0);
  b.v.assign(b.model.npoint(), Vec3::Zero());
  expect_exact_tangent(b, 9);
}

// The volume term's Gauss-Newton part is the whole tangent at rest and its
// error grows with the pressure: at rest the product matches differences
// to 1e-6, and with 1 % strain it stays within 5 %.
TEST(ImplicitSystem, VolumeTermTangentIsExactAtRestAndCloseNearIt) {
  for (const double amplitude : {0.0, 4e-4}) {
    DeformedBox b = deformed_box(soft_material(0.45, 0), amplitude, 3);
    ASSERT_TRUE(b.model.has_volume());
    ImplicitSystem system(b.model);
    system.linearise(b.x, b.v, 0, {});
    Eigen::VectorXd p = Eigen::VectorXd::Zero(3 * b.model.npoint());
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int32_t i = 0; i < b.model.npoint(); ++i)
      if (!b.model.fixed[i]) p.segment<3>(3 * i) = Vec3(u(rng), u(rng), u(rng));
    Eigen::VectorXd kp;
    system.apply(0, 0, 1, p, kp);
    const Eigen::VectorXd kfd = force_difference(b.model, b.x, b.v, p, false, 1e-8);
    EXPECT_LT((kp - kfd).norm(), (amplitude == 0 ? 1e-6 : 0.05) * kfd.norm()) << "amplitude " << amplitude;
  }
}

// The diagonal blocks are those of the operator itself.
TEST(ImplicitSystem, DiagonalBlocksAreTheOperatorsOwn) {
  for (const double nu : {0.45, 0.2}) {
    Material material = soft_material(nu, 0.01);
    material.viscous_damping = 3;
    const DeformedBox b = deformed_box(material, 5e-4, 11);
    ImplicitSystem system(b.model);
    ContactBlock c;
    c.point = {1, 2, 5};
    c.w = {0.2, 0.3, 0.5};
    c.k = 40 * Vec3(0, 0.6, 0.8) * Vec3(0, 0.6, 0.8).transpose();
    system.linearise(b.x, b.v, 0, {c});
    std::vector<Eigen::Matrix3d> blocks;
    system.diagonal_blocks(1, 2e-3, 4e-6, blocks);
    for (int32_t i : {0, 5, 17, b.model.npoint() - 1})
      for (int a = 0; a < 3; ++a) {
        Eigen::VectorXd e = Eigen::VectorXd::Zero(3 * b.model.npoint()), col;
        e[3 * i + a] = 1;
        system.apply(1, 2e-3, 4e-6, e, col);
        EXPECT_LT((col.segment<3>(3 * i) - blocks[i].col(a)).norm(), 1e-12 * blocks[i].norm())
            << "nu " << nu << " point " << i << " axis " << a;
      }
  }
}

// One step of the backend against the system assembled densely (column by
// column from the same products) and solved by Eigen's LDLT: dv agrees to
// the CG tolerance.
TEST(ImplicitEuler, OneStepMatchesADenseDirectSolveOfTheSameSystem) {
  for (const double nu : {0.45, 0.2}) {
    const DeformedBox b = deformed_box(soft_material(nu, 0.005), 5e-4, 2);
    const Model& m = b.model;
    const double h = 2e-3;
    ImplicitOptions options;
    options.cg_tolerance = 1e-12;
    options.cg_max_iterations = 1000;
    auto backend = make_reference_backend(m, {}, Integrator::ImplicitEuler, options);
    std::vector<Vec3> prev(m.npoint());
    for (int32_t i = 0; i < m.npoint(); ++i) prev[i] = b.x[i] - h * b.v[i];
    backend->set_state(b.x, prev);
    TickRequest request;
    request.dt = h;
    request.substeps = 1;
    backend->tick(request);
    std::vector<Vec3> x1;
    backend->positions(x1);

    ImplicitSystem system(m);
    std::vector<Vec3> v0 = b.v, f;
    for (int32_t i = 0; i < m.npoint(); ++i)
      if (m.fixed[i]) v0[i] = Vec3::Zero();
    system.linearise(b.x, v0, 0, {});
    reference_internal_forces(m, b.x, v0, f);
    Eigen::VectorXd kv;
    system.apply(0, 0, 1, flat(v0), kv);
    const Eigen::VectorXd rhs = h * flat(f) - h * h * kv;
    std::vector<int32_t> free;
    for (int32_t i = 0; i < 3 * m.npoint(); ++i)
      if (!m.fixed[i / 3]) free.push_back(i);
    const auto nf = static_cast<Eigen::Index>(free.size());
    Eigen::MatrixXd A(nf, nf);
    Eigen::VectorXd bf(nf);
    for (Eigen::Index c = 0; c < nf; ++c) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(3 * m.npoint()), col;
      e[free[c]] = 1;
      system.apply(1, h, h * h, e, col);
      for (Eigen::Index r = 0; r < nf; ++r) A(r, c) = col[free[r]];
      bf[c] = rhs[free[c]];
    }
    const Eigen::VectorXd dv = A.ldlt().solve(bf);
    double worst = 0;
    for (Eigen::Index c = 0; c < nf; ++c) {
      const int32_t i = free[c] / 3, a = free[c] % 3;
      const double backend_dv = (x1[i][a] - b.x[i][a]) / h - v0[i][a];
      worst = std::max(worst, std::abs(backend_dv - dv[c]));
    }
    // 1e-8 of the largest dv: the CG tolerance 1e-12 times the system's
    // condition number (~1e3 here), with margin.
    EXPECT_LT(worst, 1e-8 * dv.cwiseAbs().maxCoeff()) << "nu " << nu;
  }
}

// A mass on a spring below a fixed point, moving along it: the system is
// linear, and backward Euler's step is the closed form
//   (m + h d + h^2 k) v1 = m v0 - h k x0,  x1 = x0 + h v1.
// Without the damper the energy (k x^2 + m v^2) / 2 falls by exactly
// 1 / (1 + h^2 k / m) per step: it decays and never rises.
TEST(ImplicitEuler, SingleSpringFollowsBackwardEulersAmplificationExactly) {
  const double k = 10, m = 0.01, rest = 0.1;
  for (const double d : {0.0, 0.05}) {
    for (const double h : {1e-3, 0.05}) {  // 0.03 and 1.6 times 2/omega
      Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0, 0, -rest)}, {m, m}, {{0, 1}}, k, d, {0});
      ImplicitOptions options;
      options.cg_tolerance = 1e-14;
      auto backend = make_reference_backend(model, {}, Integrator::ImplicitEuler, options);
      double x = 0.01, v = 0;  // stretch below rest, m; velocity along -z, m/s
      backend->set_state({Vec3::Zero(), Vec3(0, 0, -rest - x)}, {Vec3::Zero(), Vec3(0, 0, -rest - x)});
      TickRequest request;
      request.dt = h;
      request.substeps = 1;
      double energy = k * x * x / 2;
      std::vector<Vec3> pos;
      for (int step = 0; step < 50; ++step) {
        const double v1 = (m * v - h * k * x) / (m + h * d + h * h * k);
        x += h * v1, v = v1;
        backend->tick(request);
        backend->positions(pos);
        const double stretch = -pos[1].z() - rest;
        // 1e-12 m: CG to 1e-14 on a system this small is exact to rounding.
        ASSERT_NEAR(stretch, x, 1e-12) << "d " << d << " h " << h << " step " << step;
        if (d == 0) {
          const double next = (k * x * x + m * v * v) / 2;
          EXPECT_NEAR(next / energy, 1 / (1 + h * h * k / m), 1e-9);
          energy = next;
        }
      }
    }
  }
}

// Where the tangent is exact (every spring stretched, no damping, no volume
// term), Newton's residual falls quadratically: each one at most 10 times
// the square of the last over the one before.
TEST(ImplicitEuler, NewtonResidualFallsQuadraticallyNearTheSolution) {
  const DeformedBox b = stretched_box(soft_material(0.25, 0), 0.05);
  ImplicitOptions options;
  options.newton_iterations = 4;
  options.cg_tolerance = 1e-13;
  options.cg_max_iterations = 2000;
  auto backend = make_reference_backend(b.model, {}, Integrator::ImplicitEuler, options);
  backend->set_state(b.x, b.x);
  TickRequest request;
  request.dt = 5e-3;
  request.substeps = 1;
  backend->tick(request);
  const std::vector<double>& r = backend->integrator_stats()->last_newton_residuals;
  ASSERT_EQ(r.size(), 4u);  // after the linearised solve and after each Newton step
  EXPECT_LT(r[1], 0.1 * r[0]);
  EXPECT_LT(r[2], 10 * r[1] * r[1] / r[0]);
  EXPECT_LT(r[2], 1e-3 * r[0]);
}

// A stiff block (E = 1 MPa) under gravity, stepped at 100 dt_crit: it stays
// finite, its energy never grows, and it comes to rest at the small-strain
// static solution within 1e-3 of the largest displacement.
TEST(ImplicitEuler, StiffModelAtHundredTimesDtCritSettlesToTheStaticSolution) {
  Material material = soft_material(0.45, 0.002);
  material.young_modulus = 1e6;
  const Vec3 g(0, 0, -9.81);
  const Model model = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 3, 3, 3), material,
                                  testing::fixed_bottom_options(g));
  const double dt_crit = estimate_critical_step(model).dt_crit;
  auto backend = make_reference_backend(model, {}, Integrator::ImplicitEuler);
  TickRequest request;
  request.dt = 100 * dt_crit;
  request.substeps = 1;
  std::vector<Vec3> x;
  for (int step = 0; step < 400; ++step) {
    backend->tick(request);
    backend->positions(x);
    for (const Vec3& p : x) ASSERT_TRUE(p.allFinite()) << "step " << step;
  }
  StaticProblem problem;
  problem.load.resize(model.npoint());
  for (int32_t p = 0; p < model.npoint(); ++p) problem.load[p] = model.mass[p] * g;
  const StaticSolution s = solve_static(model, problem);
  double largest = 0, worst = 0;
  for (int32_t p = 0; p < model.npoint(); ++p) {
    largest = std::max(largest, s.displacement[p].norm());
    worst = std::max(worst, (x[p] - model.rest_position[p] - s.displacement[p]).norm());
  }
  ASSERT_GT(largest, 0);
  EXPECT_LT(worst, 1e-3 * largest) << "sag " << largest << " m, dt " << request.dt << " s";
}

// Released from a deformed state without damping, the total energy (elastic
// plus kinetic) never rises from one step to the next, at a dt far above
// dt_crit where Verlet would blow up.
TEST(ImplicitEuler, UndampedEnergyNeverRisesAtLargeSteps) {
  const DeformedBox b = deformed_box(soft_material(0.45, 0), 8e-4, 9);
  const Model& m = b.model;
  const double h = 20 * estimate_critical_step(m).dt_crit;
  auto backend = make_reference_backend(m, {}, Integrator::ImplicitEuler);
  backend->set_state(b.x, b.x);
  TickRequest request;
  request.dt = h;
  request.substeps = 1;
  std::vector<Vec3> x, last = b.x;
  const double start = elastic_energy(m, b.x);
  double energy = start;
  for (int step = 0; step < 100; ++step) {
    backend->tick(request);
    backend->positions(x);
    double kinetic = 0;
    for (int32_t i = 0; i < m.npoint(); ++i) kinetic += m.mass[i] * (x[i] - last[i]).squaredNorm() / (2 * h * h);
    const double next = elastic_energy(m, x) + kinetic;
    // 1e-9 relative, and 1e-12 of the start once the energy has decayed to
    // rounding: the CG tolerance's share of the energy.
    EXPECT_LE(next, energy * (1 + 1e-9) + 1e-12 * start) << "step " << step;
    energy = next;
    last = x;
  }
  EXPECT_LT(energy, 1e-3 * start);  // implicit Euler's numerical damping at 20 dt_crit
}

// A CG that cannot converge (tolerance 0, two iterations) is counted in
// every step, and the run's report turns it into a warning.
TEST(ImplicitEuler, ACgThatCannotConvergeIsCountedAndWarned) {
  const DeformedBox b = deformed_box(soft_material(0.45, 0.005), 5e-4, 4);
  ImplicitOptions options;
  options.cg_tolerance = 0;
  options.cg_max_iterations = 2;
  auto backend = make_reference_backend(b.model, {}, Integrator::ImplicitEuler, options);
  backend->set_state(b.x, b.x);
  testing::run_ticks(*backend, 5, 1e-3, 2);
  const IntegratorStats& s = *backend->integrator_stats();
  EXPECT_EQ(s.steps(), 10);
  EXPECT_EQ(s.unconverged_steps, 10);
  EXPECT_GT(s.max_residual, 0);
  const nlohmann::json meta = integrator_meta(*backend);
  EXPECT_EQ(meta["name"], "implicit_euler");
  EXPECT_EQ(meta["cg_unconverged_steps"], 10);
  EXPECT_EQ(meta["cg_iterations_max"], 2);
  EXPECT_NE(integrator_warning(*backend).find("10 of 10 steps"), std::string::npos);
  EXPECT_NE(integrator_progress(*backend), "");

  options.cg_tolerance = 1e-5;
  options.cg_max_iterations = 500;
  auto converging = make_reference_backend(b.model, {}, Integrator::ImplicitEuler, options);
  converging->set_state(b.x, b.x);
  testing::run_ticks(*converging, 5, 1e-3, 2);
  EXPECT_EQ(converging->integrator_stats()->unconverged_steps, 0);
  EXPECT_EQ(integrator_warning(*converging), "");
}

// 20 implicit Euler steps of 1 ms with `preconditioner` at CG tolerance
// 1e-9: the end positions and the CG iterations of all the steps.
struct PreconditionedRun {
  std::vector<Vec3> end;
  int64_t iterations = 0;
};
PreconditionedRun run_preconditioned(const Model& model, Preconditioner preconditioner) {
  ImplicitOptions options;
  options.preconditioner = preconditioner;
  options.cg_tolerance = 1e-9;
  options.cg_max_iterations = 2000;
  auto backend = make_reference_backend(model, {}, Integrator::ImplicitEuler, options);
  testing::run_ticks(*backend, 20, 1e-3, 1);
  PreconditionedRun run;
  backend->positions(run.end);
  for (int32_t it : backend->integrator_stats()->cg_iterations) run.iterations += it;
  return run;
}

// `other` solves the same steps as block Jacobi (the runs agree within 1e-6
// of the largest displacement) in fewer than `share` of its iterations.
void expect_same_steps_in_fewer_iterations(const Model& model, Preconditioner other, double share) {
  const PreconditionedRun jacobi = run_preconditioned(model, Preconditioner::BlockJacobi);
  const PreconditionedRun run = run_preconditioned(model, other);
  double largest = 0, worst = 0;
  for (int32_t p = 0; p < model.npoint(); ++p) {
    largest = std::max(largest, (jacobi.end[p] - model.rest_position[p]).norm());
    worst = std::max(worst, (jacobi.end[p] - run.end[p]).norm());
  }
  EXPECT_GT(largest, 0);
  EXPECT_LT(worst, 1e-6 * largest);
  EXPECT_LT(static_cast<double>(run.iterations), share * static_cast<double>(jacobi.iterations))
      << "block Jacobi " << jacobi.iterations << ", " << preconditioner_name(other) << " " << run.iterations;
}

Model stiff_block(int cells) {
  Material material = soft_material(0.45, 0.002);
  material.young_modulus = 1e6;
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), cells, cells, cells), material,
                     testing::fixed_bottom_options(Vec3(0, 0, -9.81)));
}

// The rest factor needs under half of block Jacobi's iterations on a stiff block.
TEST(ImplicitEuler, RestCholeskyAndBlockJacobiAgreeAndTheFactorNeedsFewerIterations) {
  expect_same_steps_in_fewer_iterations(stiff_block(3), Preconditioner::RestCholesky, 0.5);
}

// The two-level preconditioner's coarse correction takes out the smooth
// error: under 3/5 of block Jacobi's iterations on a stiff 10^3-cell block
// (it measures half; few aggregates on a smaller block gain less).
TEST(ImplicitEuler, TwoLevelAndBlockJacobiAgreeAndTheCoarseCorrectionNeedsFewerIterations) {
  expect_same_steps_in_fewer_iterations(stiff_block(10), Preconditioner::TwoLevel, 0.6);
}

// Implicit damping on the same spring: (m + h d) v1 = m v0 - h k x0, the
// elastic force at the step's start (symplectic Euler), the damper at its
// end. With a damper that makes Verlet's dt_crit 40 times shorter than the
// undamped 2/omega, a step of 0.9 x 2/omega is stable and decays.
TEST(ImplicitDamping, SingleSpringFollowsItsClosedFormAndOnlyTheUndampedLimitBoundsTheStep) {
  const double k = 10, m = 0.01, rest = 0.1, d = 4;  // damping ratio d / (2 sqrt(k m)) = 6.3
  const double h = 0.9 * 2 * std::sqrt(m / k);
  Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0, 0, -rest)}, {m, m}, {{0, 1}}, k, d, {0});
  ImplicitOptions options;
  options.cg_tolerance = 1e-14;
  auto backend = make_reference_backend(model, {}, Integrator::ImplicitDamping, options);
  EXPECT_TRUE(backend->step_plan().has(Pass::ConjugateGradient));
  double x = 0.01, v = 0;
  backend->set_state({Vec3::Zero(), Vec3(0, 0, -rest - x)}, {Vec3::Zero(), Vec3(0, 0, -rest - x)});
  TickRequest request;
  request.dt = h;
  request.substeps = 1;
  std::vector<Vec3> pos;
  for (int step = 0; step < 60; ++step) {
    const double v1 = (m * v - h * k * x) / (m + h * d);
    x += h * v1, v = v1;
    backend->tick(request);
    backend->positions(pos);
    ASSERT_NEAR(-pos[1].z() - rest, x, 1e-12) << "step " << step;
  }
  EXPECT_LT(std::abs(x), 1e-3 * 0.01);  // it decays at 0.9 x the undamped limit

  StabilityReport report;
  report.dt_crit = 2 * std::sqrt(m / k) / 40;
  report.dt_crit_undamped = 2 * std::sqrt(m / k);
  EXPECT_EQ(check_time_step(report, h, 1, false, Integrator::ImplicitDamping), "");
  EXPECT_THROW(check_time_step(report, 1.1 * report.dt_crit_undamped, 1, false, Integrator::ImplicitDamping), Error);
  EXPECT_THROW(check_time_step(report, h, 1, false, Integrator::Verlet), Error);
  EXPECT_EQ(check_time_step(report, 100 * h, 1, false, Integrator::ImplicitEuler), "");
}

// Elastic + kinetic + gravitational energy of positions x with the step's
// increment d = x - x_prev over step h, J.
double total_energy(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& last, double h) {
  double e = elastic_energy(model, x);
  for (int32_t i = 0; i < model.npoint(); ++i)
    e += model.mass[i] * ((x[i] - last[i]).squaredNorm() / (2 * h * h) - model.gravity.dot(x[i]));
  return e;
}

// The energy above equilibrium of a cantilever released from rest under
// gravity, after `steps` steps of h, over the same at the start.
double energy_left(const Model& model, Backend& backend, double h, int steps, double equilibrium) {
  const double start = total_energy(model, model.rest_position, model.rest_position, h) - equilibrium;
  testing::run_ticks(backend, steps, h, 1);
  std::vector<Vec3> x, last;
  backend.positions(x);
  testing::run_ticks(backend, 1, h, 1);
  backend.positions(last);
  std::swap(x, last);  // x one step after `last`: the kinetic energy of that step, at (steps + 1) h
  return (total_energy(model, x, last, h) - equilibrium) / start;
}

// Numerical damping, measured: a stiff cantilever (8 x 2 x 2 cm, E = 2 MPa,
// held at x = 0, no damper, small strain) released from rest under gravity
// swings in its first mode. Verlet keeps its energy; implicit Euler takes
// the fraction h^2 w^2 / (1 + h^2 w^2) of a mode's energy per step, so that
// after n steps (1 + h^2 w^2)^-n of it is left: within 10 % in its
// logarithm (the higher modes in the released shape, a few per cent of
// the energy, decay faster).
TEST(ImplicitEuler, AReleasedCantileverLosesEnergyAtBackwardEulersRate) {
  Material material = soft_material(0.45, 0);
  material.young_modulus = 2e6;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  FixedSelector root;
  root.kind = FixedSelector::Kind::Plane;
  root.point = Vec3(1e-6, 0, 0);
  root.normal = Vec3(-1, 0, 0);
  options.fixed = {root};
  const Model model = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3(0.08, 0.02, 0.02), 8, 2, 2), material, options);
  // The equilibrium: implicit Euler at long steps damps every mode away.
  auto settle = make_reference_backend(model, {}, Integrator::ImplicitEuler);
  testing::run_ticks(*settle, 200, 0.01, 1);
  std::vector<Vec3> eq;
  settle->positions(eq);
  const double equilibrium = total_energy(model, eq, eq, 1);
  // The first mode's frequency: the Verlet run's tip period.
  auto verlet = make_cpu_backend(model, {}, testing::one_thread());
  const double dt = 2e-5;
  int32_t tip = 0;
  for (int32_t p = 0; p < model.npoint(); ++p)
    if (model.rest_position[p].x() > model.rest_position[tip].x() - 1e-12) tip = p;
  std::vector<double> z;
  std::vector<Vec3> x;
  for (int i = 0; i < 10000; ++i) {
    testing::run_ticks(*verlet, 1, dt, 1);
    verlet->positions(x);
    z.push_back(x[tip].z());
  }
  std::vector<size_t> maxima;
  for (size_t i = 1; i + 1 < z.size(); ++i)
    if (z[i] > z[i - 1] && z[i] >= z[i + 1] && z[i] > 0.5 * (eq[tip].z() + model.rest_position[tip].z()))
      if (maxima.empty() || i - maxima.back() > 100) maxima.push_back(i);
  // Released from rest, the tip starts at a maximum: the first one found
  // (z[i] is after i + 1 steps) is a period later.
  ASSERT_GE(maxima.size(), 1u);
  const double period = static_cast<double>(maxima[0] + 1) * dt, omega = 2 * std::acos(-1.0) / period;
  auto verlet_again = make_cpu_backend(model, {}, testing::one_thread());
  const double verlet_left = energy_left(model, *verlet_again, dt, static_cast<int>(period / dt), equilibrium);
  EXPECT_NEAR(verlet_left, 1, 0.02) << "Verlet without dampers keeps the energy";
  for (const double h : {1e-3, 4e-3}) {
    const int steps = static_cast<int>(std::lround(period / h));
    auto implicit = make_reference_backend(model, {}, Integrator::ImplicitEuler);
    const double left = energy_left(model, *implicit, h, steps, equilibrium);
    const double predicted = std::pow(1 + h * h * omega * omega, -(steps + 1));
    std::cout << "cantilever: period " << period << " s (omega " << omega << " rad/s), Verlet keeps " << verlet_left
              << " of its energy over a period; implicit Euler at h = " << h << " s (omega h " << omega * h
              << ") keeps " << left << ", predicted " << predicted << "\n";
    EXPECT_NEAR(std::log(left), std::log(predicted), 0.1 * std::abs(std::log(predicted))) << "h " << h;
  }
}

TEST(ImplicitEuler, OptionsOutOfRangeAreRefused) {
  const Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0, 0, -0.1)}, {1, 1}, {{0, 1}}, 1, 0, {0});
  ImplicitOptions bad;
  bad.newton_iterations = 0;
  EXPECT_THROW(make_reference_backend(model, {}, Integrator::ImplicitEuler, bad), Error);
  bad = {};
  bad.cg_max_iterations = 0;
  EXPECT_THROW(make_reference_backend(model, {}, Integrator::ImplicitEuler, bad), Error);
  BackendTool tool;
  tool.present = true;
  tool.friction.mu_s = tool.friction.mu_k = 0.3;
  ImplicitOptions newton;
  newton.newton_iterations = 2;
  EXPECT_THROW(make_reference_backend(model, tool, Integrator::ImplicitEuler, newton), Error);
  EXPECT_THROW(make_reference_backend(model, {}, Integrator::ImplicitDamping, newton), Error);
}

}  // namespace
}  // namespace implicit_test
}  // namespace organsim
