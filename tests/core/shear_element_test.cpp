// The per-tet shear element for Poisson ratios below 1/4 (Model::tet_shear_k,
// core/model/shear_element.h, docs/physics.md): the material mapping, its
// energy and forces (finite differences, rotation invariance, small-strain
// moduli), the reference backend, the CPU kernel and the scatter step
// against the double reference force, the rest state, topology rebuilds, dt_crit and its Gershgorin
// bound against the exact spectrum, and the simd kernel running it.
#include <gtest/gtest.h>

// GCC 12's AVX-512 intrinsics fill unused operands with _mm256_undefined_pd(),
// which -Wmaybe-uninitialized reports inside Eigen's dense matrix-vector
// product (a known false positive; the dense eigensolver below uses it).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <Eigen/Eigenvalues>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/model/shear_element.h"
#include "core/model/stiffness.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/reference_forces.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"
#include "core/util/error.h"
#include "core/validation/static_solve.h"
#include "tests/core/force_law_checks.h"
#include "tests/core/stability_test_util.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace shear_element_test {
namespace {

Material shear_material(double nu = 0.1, ShearFormulation formulation = ShearFormulation::Smoothed) {
  Material m = testing::soft_material(nu);
  m.shear_formulation = formulation;
  return m;
}

Model shear_model(unsigned seed, int cells, double nu = 0.1, int32_t chunk = kDefaultChunkSize,
                  const Vec3& gravity = Vec3::Zero(), ShearFormulation formulation = ShearFormulation::Smoothed) {
  return build_model(testing::jittered_box(cells, 0.05, 0.25, seed), shear_material(nu, formulation),
                     testing::fixed_bottom_options(gravity, chunk));
}

// Both formulations of the element, for the kernel tests to loop over: the
// smoothed one (default, with the kernels' per-point pass) and per tet.
constexpr ShearFormulation kFormulations[] = {ShearFormulation::Smoothed, ShearFormulation::PerTet};

double largest_norm(const std::vector<Vec3>& v) {
  double s = 0;
  for (const Vec3& f : v) s = std::max(s, f.norm());
  return s;
}

// Below 1/4 the springs carry lambda and the element mu - lambda; from 1/4
// up the old rule (springs mu, volume lambda - mu). The parts give back the
// asked E and nu, are never negative, and meet at 1/4.
TEST(ShearElement, MappingGivesTheAskedModuliAndIsContinuousAtAQuarter) {
  for (double nu : {0.0, 0.1, 0.2, 0.2499, 0.25, 0.3, 0.45}) {
    Material m = shear_material(nu);
    const EffectiveElasticity e = effective_elasticity(m);
    EXPECT_NEAR(e.young_modulus, m.young_modulus, 1e-9 * m.young_modulus) << nu;
    EXPECT_NEAR(e.poisson_ratio, nu, 1e-12) << nu;
    EXPECT_GE(spring_modulus(m), 0) << nu;
    EXPECT_GE(volume_term_modulus(m), 0) << nu;
    EXPECT_GE(shear_element_modulus(m), 0) << nu;
    EXPECT_EQ(shear_element_modulus(m) > 0, nu < 0.25) << nu;
  }
  // 1e-9 below: the moduli's slope in nu is of order E, so they differ by
  // ~E 1e-9 (tolerance ten times that); a jump would be of order E.
  Material below = shear_material(0.25 - 1e-9), at = shear_material(0.25);
  const double step = 10 * 1e-9 * at.young_modulus;
  EXPECT_NEAR(spring_modulus(below), spring_modulus(at), step);
  EXPECT_NEAR(shear_element_modulus(below), 0, step);
  // nu = 0: no springs' stiffness at all, the element is the whole material.
  Material zero = shear_material(0.0);
  EXPECT_EQ(spring_modulus(zero), 0.0);
  EXPECT_DOUBLE_EQ(shear_element_modulus(zero), zero.young_modulus / 2);

  const Model model = shear_model(1, 3);
  EXPECT_TRUE(model.has_shear_element());
  const nlohmann::json meta = elasticity_json(model.material);
  EXPECT_EQ(meta["volume_formulation"], "none");
  EXPECT_DOUBLE_EQ(meta["shear_element_modulus"].get<double>(), shear_element_modulus(model.material));
  EXPECT_FALSE(model.has_volume());
  EXPECT_EQ(model.tet_shape_gradient.size(), model.tet_points.size());
  EXPECT_FALSE(shear_model(1, 3, 0.3).has_shear_element());
}

// Every tet of an affinely deformed mesh has the same F, and linear shape
// functions reproduce it exactly, so the element's energy is exactly
// mu_e V [(|F|^2 - 3) / 2 - ln det F] at any strain (1e-10: rounding of a
// sum over ~400 tets). At small strain that is the linear solid with Lame
// (0, mu_e): a simple shear gamma stores mu_e V gamma^2 / 2 (shear modulus
// mu_e), a uniaxial strain eps stores mu_e V eps^2 (lambda = 0).
TEST(ShearElement, AffineDeformationsStoreTheContinuumEnergy) {
  const Model model = shear_model(3, 4, 0.0);
  const double mu = shear_element_modulus(model.material), volume = model.rest_volume();
  auto energy_at = [&](const Eigen::Matrix3d& F) {
    std::vector<Vec3> x(model.npoint());
    for (int32_t i = 0; i < model.npoint(); ++i) x[i] = F * model.rest_position[i] + Vec3(0.3, -0.2, 0.1);
    return shear_element_energy(model, x);
  };
  Eigen::Matrix3d F;
  F << 1.3, 0.2, -0.1, 0.05, 0.8, 0.3, 0.1, -0.2, 1.1;
  const double expected = mu * volume * ((F.squaredNorm() - 3) / 2 - std::log(F.determinant()));
  EXPECT_NEAR(energy_at(F), expected, 1e-10 * expected);
  // Small strain, 1e-4: the finite-strain terms are 1e-4 of the energy.
  const double g = 1e-4;
  Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
  shear(0, 1) = g;
  EXPECT_NEAR(energy_at(shear), mu * volume * g * g / 2, 1e-3 * mu * volume * g * g / 2);
  Eigen::Matrix3d stretch = Eigen::Matrix3d::Identity();
  stretch(2, 2) += g;
  EXPECT_NEAR(energy_at(stretch), mu * volume * g * g, 1e-3 * mu * volume * g * g);
}

// The reference force is minus the gradient of the energy. Central
// differences with h = 1e-8 m on a 1 mm deformation: truncation ~h^2 /
// (1 mm)^2 = 1e-10 relative, rounding ~1e-16 E / h; 1e-6 of the largest
// force covers both. nu = 0 and 0.2: element only, and element + springs.
TEST(ShearElement, ReferenceForceIsMinusTheEnergyGradient) {
  for (double nu : {0.0, 0.2}) {
    const Model model = shear_model(2, 3, nu);
    std::vector<Vec3> x, x_prev;
    testing::random_state(model, 7, 1e-4, x, x_prev);
    std::vector<Vec3> force, zero(x.size(), Vec3::Zero());
    reference_internal_forces(model, x, zero, force);
    const double scale = largest_norm(force);
    ASSERT_GT(scale, 0);
    const double h = 1e-8;
    for (int32_t i = 0; i < model.npoint(); i += 5) {
      for (int k = 0; k < 3; ++k) {
        std::vector<Vec3> plus = x, minus = x;
        plus[i][k] += h;
        minus[i][k] -= h;
        const double gradient = (elastic_energy(model, plus) - elastic_energy(model, minus)) / (2 * h);
        EXPECT_NEAR(force[i][k], -gradient, 1e-6 * scale) << "nu " << nu << " point " << i << " axis " << k;
      }
    }
  }
}

// Crushed along z to a stretch s (laterals held), down to flat and inverted:
// the energy falls all the way from s = -0.5 to 1, so the element pushes
// back at every s (a St Venant-Kirchhoff energy on the Green strain is
// lowest again at s = 0 and -1, and let a liver at nu = 0 collapse under its
// own weight); the reference force is its gradient there too, on both sides
// of J = force_law::kShearElementMinJ (central differences as above, 1e-6 of the
// largest force); and one kernel step from the crushed state agrees with it
// (double, 1e-12 of the force increment).
TEST(ShearElement, ResistsCompressionUpToAndThroughInversion) {
  const Model model = shear_model(6, 3, 0.0);
  auto crushed = [&](double s) {
    std::vector<Vec3> x = model.rest_position;
    for (Vec3& p : x) p.z() *= s;
    return x;
  };
  double previous = shear_element_energy(model, crushed(-0.5));
  for (double s = -0.45; s <= 1.0 + 1e-12; s += 0.05) {
    const double e = shear_element_energy(model, crushed(s));
    EXPECT_LT(e, previous) << "stretch " << s;
    previous = e;
  }
  for (double s : {0.7, 0.3, -0.2}) {
    const std::vector<Vec3> x = crushed(s);
    std::vector<Vec3> force, zero(x.size(), Vec3::Zero());
    reference_internal_forces(model, x, zero, force);
    const double scale = largest_norm(force), h = 1e-8;
    for (int32_t i = 0; i < model.npoint(); i += 3) {
      for (int k = 0; k < 3; ++k) {
        std::vector<Vec3> plus = x, minus = x;
        plus[i][k] += h;
        minus[i][k] -= h;
        const double gradient = (elastic_energy(model, plus) - elastic_energy(model, minus)) / (2 * h);
        EXPECT_NEAR(force[i][k], -gradient, 1e-6 * scale) << "stretch " << s << " point " << i << " axis " << k;
      }
    }
    const testing::StepError e = testing::kernel_step_error(model, x, x, 1e-4, Precision::Double);
    EXPECT_LT(e.worst, 1e-15 + 1e-12 * e.largest) << "stretch " << s;
  }
}

// A rigid rotation (50 degrees) and translation strains nothing: no force,
// in the reference and in the kernel in both precisions. The scale
// is the force of a 1 % stretch; the rotation's must be below 1e-9 of it in
// double and 1e-4 in float (rotated positions rounded to ~6e-8 relative).
TEST(ShearElement, RigidRotationHasNoForce) {
  for (ShearFormulation formulation : kFormulations) {
    SCOPED_TRACE(shear_formulation_name(formulation));
    const Model model = shear_model(4, 3, 0.0, kDefaultChunkSize, Vec3::Zero(), formulation);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(50 * M_PI / 180, Vec3(1, 2, 3).normalized()).toRotationMatrix();
    std::vector<Vec3> rotated(model.npoint()), stretched(model.npoint()), zero(model.npoint(), Vec3::Zero());
    for (int32_t i = 0; i < model.npoint(); ++i) {
      rotated[i] = R * model.rest_position[i] + Vec3(0.01, 0.02, -0.03);
      stretched[i] = Vec3(1.01, 1, 1).cwiseProduct(model.rest_position[i]);
    }
    std::vector<Vec3> force;
    reference_internal_forces(model, stretched, zero, force);
    const double scale = largest_norm(force);
    ASSERT_GT(scale, 0);
    reference_internal_forces(model, rotated, zero, force);
    EXPECT_LT(largest_norm(force), 1e-9 * scale);
    // The kernel: one step at zero velocity; every point stays where the
    // rotation put it, to the force tolerance times dt^2 / m.
    const double dt = 1e-4;
    double min_mass = 1e300;
    for (double mass : model.mass) min_mass = std::min(min_mass, mass);
    const Model free_model = build_model(testing::jittered_box(3, 0.05, 0.25, 4), shear_material(0.0, formulation), {});
    ASSERT_EQ(free_model.rest_position, model.rest_position);  // the same mesh, no fixed points
    for (Precision precision : {Precision::Double, Precision::Float}) {
      auto backend = make_cpu_backend(free_model, {}, {precision, 1});
      backend->set_state(rotated, rotated);
      testing::run_ticks(*backend, 1, dt, 1);
      std::vector<Vec3> after;
      backend->positions(after);
      double worst = 0;
      for (int32_t i = 0; i < model.npoint(); ++i) worst = std::max(worst, (after[i] - rotated[i]).norm());
      // Drag acts on the zero velocity: nothing. The motion is dt^2 f / m.
      const bool dbl = precision == Precision::Double;
      EXPECT_LT(worst, (dbl ? 1e-9 : 1e-4) * scale * dt * dt / min_mass + (dbl ? 1e-15 : 1e-8))
          << (dbl ? "double" : "float");
    }
  }
}

// The reference backend and the kernel (double and float) against Verlet on
// the reference force: one step from a deformed, moving state, for two chunk sizes (padding, lane
// groups), with gravity, in both formulations. Tolerances as in
// force_law_checks.h (double: summation order, 1e-12 of the force
// increment; float: rounding of positions, 1e-4 of it plus 1e-8 m); the
// smoothed part's extra sums (P(Fbar) over ~20 tets per point, then 4
// corners) are of the same order as the per-tet ones and need no more.
TEST(ShearElement, StepsMatchTheReferenceForceOnRandomMeshes) {
  for (ShearFormulation formulation : kFormulations) {
    SCOPED_TRACE(shear_formulation_name(formulation));
    testing::expect_steps_match_the_reference_force([formulation](unsigned seed, int32_t chunk) {
      return shear_model(seed, 5, 0.1, chunk, Vec3(0.3, -1, -9.81), formulation);
    });
  }
}

// The smoothed part is what the comparison above is about:
// on its random states it moves the force by much more than the tolerance
// (the two formulations' forces differ by over 1 % of the largest force).
TEST(ShearElement, SmoothedAndPerTetForcesDifferOnTheTestStates) {
  const Model smoothed = shear_model(1, 5, 0.1), per_tet = shear_model(1, 5, 0.1, kDefaultChunkSize, Vec3::Zero(),
                                                                        ShearFormulation::PerTet);
  ASSERT_TRUE(smoothed.has_smoothed_shear());
  ASSERT_FALSE(per_tet.has_smoothed_shear());
  std::vector<Vec3> x, x_prev, a, b, zero(smoothed.npoint(), Vec3::Zero());
  testing::random_state(smoothed, 1, 1e-4, x, x_prev);
  reference_internal_forces(smoothed, x, zero, a);
  reference_internal_forces(per_tet, x, zero, b);
  double worst = 0;
  for (int32_t i = 0; i < smoothed.npoint(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
  EXPECT_GT(worst, 1e-2 * largest_norm(a));
}

// The kernel's strain comes from displacements, so the rest state is
// exactly force-free in either precision and formulation (the smoothed
// part's Fbar - I is a sum of exact zeros, and P(I) = I - I = 0): 1000
// steps without gravity must not move a bit.
TEST(ShearElement, RestStateIsExactlyForceFree) {
  for (ShearFormulation formulation : kFormulations) {
    const Model model = shear_model(4, 5, 0.05, kDefaultChunkSize, Vec3::Zero(), formulation);
    for (Precision precision : {Precision::Double, Precision::Float}) {
      auto backend = make_cpu_backend(model, {}, {precision, 1});
      testing::run_ticks(*backend, 100, 1e-4, 10);
      std::vector<Vec3> x;
      backend->positions(x);
      for (int32_t i = 0; i < model.npoint(); ++i)
        ASSERT_EQ(x[i], model.rest_position[i]) << shear_formulation_name(formulation) << ", point " << i;
    }
  }
}

// Two threads give bitwise the same trajectory as one: the smoothing pass
// sums each point's tet slots in a fixed order and the force pass only reads
// its output after the barrier. 200 steps from a deformed, moving state
// under gravity, chunks of 16 points so that both threads have many chunks,
// in both precisions and formulations.
TEST(ShearElement, TwoThreadsAreBitIdenticalToOne) {
  const double dt = 1e-4;
  for (ShearFormulation formulation : kFormulations) {
    const Model model = shear_model(2, 5, 0.1, 16, Vec3(0, 0, -9.81), formulation);
    ASSERT_GT(model.layout.nchunk, 4);
    std::vector<Vec3> x, x_prev;
    testing::random_state(model, 2, dt, x, x_prev);
    for (Precision precision : {Precision::Double, Precision::Float}) {
      std::vector<Vec3> out[2];
      for (int threads : {1, 2}) {
        auto backend = make_cpu_backend(model, {}, {precision, threads});
        backend->set_state(x, x_prev);
        testing::run_ticks(*backend, 20, dt, 10);
        backend->positions(out[threads - 1]);
      }
      for (int32_t i = 0; i < model.npoint(); ++i)
        ASSERT_EQ(out[0][i], out[1][i]) << shear_formulation_name(formulation)
                                        << (precision == Precision::Double ? ", double" : ", float") << ", point " << i;
    }
  }
}

// The scatter step that bench times runs the same physics: 200 steps of both
// in double from rest under gravity agree to rounding, in both formulations.
TEST(ShearElement, ScatterStepMatchesTheReference) {
  for (ShearFormulation formulation : kFormulations) {
    const Model model = shear_model(5, 4, 0.1, kDefaultChunkSize, Vec3(0, 0, -9.81), formulation);
    const testing::PathDifference d = testing::scatter_against_reference(model, 200, 1e-4);
    ASSERT_GT(d.motion, 1e-6);
    // Summation order over 200 steps: ~1e-12 of the motion.
    EXPECT_LT(d.worst, 1e-9 * d.motion) << shear_formulation_name(formulation);
  }
}

// A cut rewrites tets' vertices to copies of the same rest points: the
// rebuilt Model keeps one shape-gradient set per tet, equal to the old one
// (same rest geometry), the kernel rebuilt from it is still exactly at rest,
// and its forces match the reference on a deformed state.
TEST(ShearElement, RebuildAfterACutKeepsTheElement) {
  for (ShearFormulation formulation : kFormulations) {
    SCOPED_TRACE(shear_formulation_name(formulation));
    const Model model =
        build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 4, 4, 4), shear_material(0.1, formulation), {});
    const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.02));
    ASSERT_GT(cut.npoint(), model.npoint());
    ASSERT_TRUE(cut.has_shear_element());
    ASSERT_EQ(cut.tet_shape_gradient.size(), model.tet_shape_gradient.size());
    for (int32_t t = 0; t < cut.ntet(); ++t) {
      EXPECT_DOUBLE_EQ(cut.tet_shear_k[t], model.tet_shear_k[t]) << t;
      for (int i = 0; i < 4; ++i) EXPECT_LT((cut.tet_shape_gradient[t][i] - model.tet_shape_gradient[t][i]).norm(), 1e-9) << t;
    }
    for (Precision precision : {Precision::Double, Precision::Float}) {
      auto backend = make_cpu_backend(model, {}, {precision, 1});
      backend->rebuild(cut);
      testing::run_ticks(*backend, 20, 1e-4, 5);
      std::vector<Vec3> x;
      backend->positions(x);
      for (int32_t i = 0; i < cut.npoint(); ++i) ASSERT_EQ(x[i], cut.rest_position[i]) << i;
    }
    // The cut model's K_a (smoothed) are those of its own tets: the kernel
    // rebuilt from it matches the reference on a deformed, moving state
    // (tolerances as in StepsMatchTheReferenceForceOnRandomMeshes).
    EXPECT_EQ(cut.has_smoothed_shear(), formulation == ShearFormulation::Smoothed);
    {
      const double dt = 1e-4;
      std::vector<Vec3> x, x_prev;
      testing::random_state(cut, 3, dt, x, x_prev);
      for (Precision precision : {Precision::Double, Precision::Float}) {
        auto backend = make_cpu_backend(model, {}, {precision, 1});
        backend->rebuild(cut);
        backend->set_state(x, x_prev);
        testing::run_ticks(*backend, 1, dt, 1);
        std::vector<Vec3> after, v(x.size()), force;
        backend->positions(after);
        for (size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - x_prev[i]) / dt;
        reference_internal_forces(cut, x, v, force);
        double worst = 0, largest = 0;
        for (int32_t i = 0; i < cut.npoint(); ++i) {
          const double w = dt * dt * cut.inv_mass[i];
          const Vec3 expected = x[i] + (1 - cut.viscous_damping * dt) * (x[i] - x_prev[i]) + w * force[i];
          worst = std::max(worst, (after[i] - expected).norm());
          largest = std::max(largest, w * force[i].norm());
        }
        const bool dbl = precision == Precision::Double;
        EXPECT_LT(worst, dbl ? 1e-15 + 1e-12 * largest : 1e-8 + 1e-4 * largest) << (dbl ? "double" : "float");
      }
    }
    // The two halves move apart freely: pull the copies 1 mm along +x, the
    // force on the cut face's originals must not see it (no tet joins them).
    std::vector<Vec3> x = cut.rest_position, zero(x.size(), Vec3::Zero()), moved, still;
    reference_internal_forces(cut, x, zero, still);
    for (int32_t p = model.npoint(); p < cut.npoint(); ++p) x[p].x() += 1e-3;
    reference_internal_forces(cut, x, zero, moved);
    for (int32_t p = model.npoint(); p < cut.npoint(); ++p) {
      const int32_t o = cut.origin[p];
      EXPECT_LT((moved[o] - still[o]).norm(), 1e-12) << o;
    }
  }
}

// The static solve's stiffness (the validation suite's) is the derivative
// of the reference force, per-tet and smoothed: its solution u for a random
// load f satisfies K u = f with K from central differences of the reference
// force (exact to ~1e-7 of K, see above), to 1e-5 of |f|. The two forms
// must also differ, or the smoothing would be missing from one side.
TEST(ShearElement, StaticSolveIsTheLinearisedReferenceForce) {
  std::vector<Eigen::VectorXd> solutions;
  for (ShearFormulation form : {ShearFormulation::PerTet, ShearFormulation::Smoothed}) {
    Material m = shear_material(0.1);
    m.shear_formulation = form;
    const Model model = build_model(testing::jittered_box(3, 0.05, 0.25, 9), m, testing::fixed_bottom_options());
    ASSERT_EQ(model.has_smoothed_shear(), form == ShearFormulation::Smoothed);
    std::vector<int32_t> free_dof;
    const Eigen::MatrixXd K = testing::dense_rest_stiffness(model, free_dof);
    StaticProblem problem;
    problem.load.assign(model.npoint(), Vec3::Zero());
    Eigen::VectorXd f(free_dof.size()), u(free_dof.size());
    for (size_t r = 0; r < free_dof.size(); ++r) {
      f[r] = std::sin(1.7 * static_cast<double>(r) + 0.3) * 1e-3;  // N
      problem.load[free_dof[r] / 3][free_dof[r] % 3] = f[r];
    }
    const StaticSolution solution = solve_static(model, problem);
    for (size_t r = 0; r < free_dof.size(); ++r) u[r] = solution.displacement[free_dof[r] / 3][free_dof[r] % 3];
    EXPECT_LT((K * u - f).norm(), 1e-5 * f.norm()) << shear_formulation_name(form);
    solutions.push_back(u);
  }
  EXPECT_GT((solutions[0] - solutions[1]).norm(), 0.01 * solutions[0].norm());
}

// dt_crit's power iteration and Gershgorin rows include the element: on a
// small model the exact largest eigenvalue of M^-1 K (dense, from the
// reference force) is matched by the power iteration to 1 % (its stopping
// rule, a change under 1e-5 in 20 iterations, can stop short of a close
// second eigenvalue; the finite-difference K is exact to ~1e-7), and the Gershgorin
// bound is above it. nu = 0: the element is all of K.
TEST(ShearElement, CriticalStepAndGershgorinBoundHoldAgainstTheExactSpectrum) {
  for (double nu : {0.0, 0.15}) {
    Material m = testing::undamped_material(3000);
    m.poisson_ratio = nu;
    const Model model = testing::stability_box(3, 0.03, m, 0.2, 5);
    ASSERT_TRUE(model.has_shear_element());
    std::vector<int32_t> free_dof;
    const Eigen::MatrixXd K = testing::dense_rest_stiffness(model, free_dof);
    Eigen::VectorXd inv_sqrt_m(free_dof.size());
    for (size_t r = 0; r < free_dof.size(); ++r) inv_sqrt_m[r] = 1 / std::sqrt(model.mass[free_dof[r] / 3]);
    const Eigen::MatrixXd W = inv_sqrt_m.asDiagonal() * K * inv_sqrt_m.asDiagonal();  // M^-1/2 K M^-1/2
    const double exact = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(W, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
    const StabilityReport r = estimate_critical_step(model);
    EXPECT_NEAR(r.lambda_max, exact, 1e-2 * exact) << "nu " << nu;
    EXPECT_GE(r.lambda_gershgorin, exact) << "nu " << nu;
    if (nu == 0) {
      EXPECT_GT(r.share_shear, 0.99);
    }
  }
}

// dt_crit is the scheme's own threshold with the element: just under it a
// perturbation stays bounded, just over it grows (2 % either side).
TEST(ShearElement, CriticalStepIsTheIntegratorsThreshold) {
  Material m = testing::undamped_material(3000);
  m.poisson_ratio = 0.05;
  const Model model = testing::stability_box(3, 0.03, m, 0.2, 5);
  const StabilityReport r = estimate_critical_step(model);
  EXPECT_TRUE(r.converged);
  EXPECT_FALSE(testing::perturbation_grows(model, 0.98 * r.dt_crit));
  EXPECT_TRUE(testing::perturbation_grows(model, 1.02 * r.dt_crit));
}

// Both formulations; the plan names the smoothing pass (before the force
// pass, like the nodal volume term's) only for the smoothed one.
TEST(ShearElement, ModelsWithItRunOnTheSimdKernel) {
  for (ShearFormulation formulation : kFormulations) {
    SCOPED_TRACE(shear_formulation_name(formulation));
    const Model model = shear_model(1, 3, 0.1, kDefaultChunkSize, Vec3::Zero(), formulation);
    EXPECT_EQ(simd_kernel_unsupported(model), "");
    auto backend = make_cpu_backend(model, {}, {Precision::Float, 1});
    const std::string kernel = "simd (" + default_simd_target().name + ") kernel";
    EXPECT_NE(backend->device().find(kernel), std::string::npos) << backend->device();
    const Plan plan = backend->plan();
    const bool smoothed = formulation == ShearFormulation::Smoothed;
    std::vector<std::string> names;
    for (const PassInfo& p : plan.passes) names.push_back(p.name);
    const std::vector<std::string> expected =
        smoothed ? std::vector<std::string>{"shear-smoothing", "springs", "shear-element", "integrate"}
                 : std::vector<std::string>{"springs", "shear-element", "integrate"};
    EXPECT_EQ(names, expected);
  }
}

}  // namespace
}  // namespace shear_element_test
}  // namespace organsim
