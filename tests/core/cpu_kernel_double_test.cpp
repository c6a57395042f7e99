// The simd double kernel, on every target compiled in that this CPU runs
// (each its own test case), against the reference (reference_backend.h's
// Verlet on the reference forces): forces per point on random meshes, 1000-step trajectories for
// every scene variant, threads, the rest state, a rebuild after a cut, each
// with every per-tet term (volume per tet or nodal, shear element), and
// what the kernel says of itself. The two sum the same terms in different orders
// (and the kernel's 1/|l| is Newton steps from an estimate, not a square
// root and a division), so they agree to rounding, not bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/model/model_rebuild.h"
#include "core/model/nodal_volume.h"
#include "core/model/shear_element.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/util/error.h"
#include "tests/core/cpu_kernel_test_util.h"

namespace organsim {
namespace cpu_kernel_double_test {
namespace {

using testing::kSize;
using testing::random_model;
using testing::VolumeTerm;

// Each simd target this CPU runs is its own test case.
class CpuKernelDouble : public ::testing::TestWithParam<std::string> {
 protected:
  CpuBackendOptions fast() const { return testing::fast_kernel(GetParam(), Precision::Double); }
};
INSTANTIATE_TEST_SUITE_P(Kernels, CpuKernelDouble, ::testing::ValuesIn(testing::fast_kernels()), testing::kernel_test_name);

// Per point, the sum of the magnitudes its force is summed from, before any
// cancellation: per spring k max(L, r) (the stretch k (L - r) is the
// difference of two such) and d |dv| / dt, per tet k_v max(|V|, |V_r|)
// |dV/dx_i| (likewise) or, with the nodal term, the mean over its vertices
// a of k_a max(|V_a|, V_a^r) times |dV/dx_i|, and m |g|. Rounding in either
// kernel is a few ulps of each of these.
std::vector<double> force_term_magnitudes(const Model& m, const std::vector<Vec3>& x,
                                          const std::vector<Vec3>& x_prev, double dt) {
  std::vector<double> sum(m.npoint());
  for (int32_t i = 0; i < m.npoint(); ++i) sum[i] = m.mass[i] * m.gravity.norm();
  for (int32_t s = 0; s < m.nspring(); ++s) {
    const auto [a, b] = m.spring_ends[s];
    const double length = (x[b] - x[a]).norm();
    const double dv = ((x[b] - x_prev[b]) - (x[a] - x_prev[a])).norm() / dt;
    const double term = m.spring_k[s] * std::max(length, m.spring_rest[s]) + m.spring_d[s] * dv;
    sum[a] += term;
    sum[b] += term;
  }
  std::vector<double> nodal;
  if (m.has_nodal_volume()) nodal_volumes(m, x, nodal);
  for (int32_t t = 0; t < (m.has_volume() ? m.ntet() : 0); ++t) {
    const auto& v = m.tet_points[t];
    const Vec3 e1 = x[v[1]] - x[v[0]], e2 = x[v[2]] - x[v[0]], e3 = x[v[3]] - x[v[0]];
    double pressure = 0;
    if (m.has_nodal_volume()) {
      for (int32_t a : v) pressure += m.point_volume_k[a] * std::max(std::abs(nodal[a]), m.point_rest_volume[a]) / 4;
    } else {
      pressure = m.tet_k[t] * std::max(std::abs(e1.dot(e2.cross(e3)) / 6), m.tet_rest_volume[t]);
    }
    const Vec3 g1 = e2.cross(e3) / 6, g2 = e3.cross(e1) / 6, g3 = e1.cross(e2) / 6;
    const double grad[4] = {(g1 + g2 + g3).norm(), g1.norm(), g2.norm(), g3.norm()};
    for (int k = 0; k < 4; ++k) sum[v[k]] += pressure * grad[k];
  }
  if (m.has_shear_element()) {
    // The shear element: k_t (|F| + |phi'(J)| |cof F| + its damper's
    // (tau / (dt J_d)) 2 |G| |cof F|^2) |g_i|, G = sum_i (x_i - x_prev_i)
    // g_i^T, the smoothed part's corner stresses bounded alike.
    for (int32_t t = 0; t < m.ntet(); ++t) {
      const auto& v = m.tet_points[t];
      const Eigen::Matrix3d F = deformation_gradient(m, t, x);
      const Eigen::Matrix3d cof = force_law::shear_cofactor(F);
      Eigen::Matrix3d G = Eigen::Matrix3d::Zero();
      for (int32_t a : v) G += (x[a] - x_prev[a]) * shape_gradient_of(m, t, a).transpose();
      const double J = F.determinant(), jd = std::max(J, force_law::kShearElementMinJ);
      const double stress = F.norm() + std::abs(force_law::shear_barrier_slope(J)) * cof.norm();
      const double damper = m.shear_damping_time / dt / jd * 2 * G.norm() * cof.squaredNorm();
      for (int32_t a : v) sum[a] += m.tet_shear_k[t] * (2 * stress + damper) * shape_gradient_of(m, t, a).norm();
    }
  }
  return sum;
}

TEST_P(CpuKernelDouble, OneStepForcesMatchTheReferenceOnRandomMeshesToRounding) {
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  testing::for_each_one_step_against_the_reference(
      fast(), [](const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev, double dt,
                 const std::vector<Vec3>& ref, const std::vector<Vec3>& got) {
        const auto terms = force_term_magnitudes(model, x, x_prev, dt);
        for (int32_t i = 0; i < model.npoint(); ++i) {
          // Both compute the increment (1 - alpha dt) d + dt^2 F / m; allowed:
          // 64 ulps of its parts before cancellation (a few ulps per term in
          // each kernel, summed over ~40 terms in two different orders), plus
          // 2 ulps of x for positions() rounding X + u either way. The second
          // dominates (1 ulp of 5 cm is 7e-18 m against increments of ~5e-6 m)
          // and is what was measured: at most 1 ulp of x, with either volume
          // term (0.76 and 0.63 ulps). A kernel off by one part in 1e10 of a
          // spring force would fail here.
          const double parts = (x[i] - x_prev[i]).norm() + model.inv_mass[i] * dt * dt * terms[i];
          ASSERT_LE((got[i] - ref[i]).norm(), 64 * kEps * parts + 2 * kEps * x[i].norm()) << "point " << i;
        }
      });
}

TEST_P(CpuKernelDouble, ThousandStepTrajectoriesTrackTheReferenceInEverySceneVariant) {
  // Rounding differences of a few ulps per step, carried by a damped
  // stable system over 1000 steps: measured up to 7.6e-17 m (about 10 ulps
  // of a 5 cm coordinate) with the per-tet term, 1.0e-17 m with the nodal
  // term. Tolerance 1e-12 of the box edge (5e-14 m), seven orders below the
  // float kernel's. The reaction sums the same per-point terms: measured
  // 7.5e-16 relative (per tet), 2.2e-15 (nodal); tolerance 1e-12.
  for (VolumeTerm volume : testing::kEveryTerm)
    testing::expect_scenes_track_the_reference(fast(), 1e-12 * kSize, 1e-12, volume);
}

TEST_P(CpuKernelDouble, TwoThreadsGiveBitIdenticalResultsToOne) {
  testing::expect_two_threads_bit_identical_to_one(fast());
}

TEST_P(CpuKernelDouble, RestStateStaysPutWithoutGravity) {
  testing::expect_rest_state_stays_put(fast());
}

TEST_P(CpuKernelDouble, KeepsTrackingTheReferenceAfterACut) {
  // As for the trajectories above (600 steps; measured 2e-17 m per tet, 3.3e-17 m nodal).
  testing::expect_cut_run_tracks_the_reference(fast(), 1e-12 * kSize);
}

TEST(CpuKernelDoubleChoice, TheKernelSaysItsTargetAndLanes) {
  const Model wide = random_model(1, 3, VolumeTerm::PerTet, true);
  const Model nodal = random_model(1, 3, VolumeTerm::Nodal, true);
  const SimdTarget best = simd_targets_supported().front();
  // By default the best target, and device() says so.
  const std::string auto_wide = make_cpu_backend(wide, {}, {Precision::Double, 1})->device();
  const std::string auto_nodal = make_cpu_backend(nodal, {}, {Precision::Double, 1})->device();
  EXPECT_NE(auto_wide.find("simd (" + best.name + ") kernel"), std::string::npos) << auto_wide;
  EXPECT_NE(auto_nodal.find("simd (" + best.name + ") kernel"), std::string::npos) << auto_nodal;
  // Each target's lanes: the register's width over a double's.
  for (const SimdTarget& target : simd_targets_supported()) {
    const Plan plan = make_cpu_backend(wide, {}, testing::fast_kernel(target.name, Precision::Double))->plan();
    const int lanes = target.name == "avx3" ? 8 : target.name == "avx2" ? 4 : target.name == "scalar" ? 1 : 2;
    EXPECT_NE(plan.passes.back().detail.find(std::to_string(lanes) + " double lanes"), std::string::npos)
        << target.name << ": " << plan.passes.back().detail;
  }
}

}  // namespace
}  // namespace cpu_kernel_double_test
}  // namespace organsim
