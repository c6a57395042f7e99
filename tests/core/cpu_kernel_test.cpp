// The simd float kernel, on every target compiled in that this CPU runs
// (each its own test case), against the double-precision reference
// (reference_backend.h's Verlet): forces per point on random meshes, 1000-step
// trajectories for every scene variant, threads, the rest state, a rebuild
// after a cut, each with every per-tet term (volume per tet or nodal, shear
// element); and the models and plans the kernel refuses.
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <random>

#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/step_plan.h"
#include "core/run/run.h"
#include "core/util/error.h"
#include "tests/core/cpu_kernel_test_util.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace cpu_kernel_test {
namespace {

using testing::kSize;
using testing::random_model;
using testing::VolumeTerm;

// Each simd target this CPU runs is its own test case.
class CpuKernel : public ::testing::TestWithParam<std::string> {
 protected:
  CpuBackendOptions fast(int threads = 1) const { return testing::fast_kernel(GetParam(), Precision::Float, threads); }
};
INSTANTIATE_TEST_SUITE_P(Kernels, CpuKernel, ::testing::ValuesIn(testing::fast_kernels()), testing::kernel_test_name);

TEST_P(CpuKernel, OneStepForcesMatchTheDoubleReferenceOnRandomMeshes) {
  testing::for_each_one_step_against_the_reference(
      fast(), [](const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>&, double,
                 const std::vector<Vec3>& ref, const std::vector<Vec3>& got) {
        // Compare the step increments dt^2 F/m + (1 - alpha dt) d per point.
        double scale = 0, worst = 0;
        for (int32_t i = 0; i < model.npoint(); ++i) scale = std::max(scale, (ref[i] - x[i]).norm());
        for (int32_t i = 0; i < model.npoint(); ++i)
          worst = std::max(worst, ((got[i] - x[i]) - (ref[i] - x[i])).norm());
        // Float: positions carry ~6e-8 relative rounding, so an edge vector
        // of 8 mm (and the spring stretch and tet volume from it) is off by
        // ~1e-9 m against stretches of ~1e-4 m: ~1e-5 of the force; the
        // nodal volumes, sums of ~24 tet volumes, add ~24 roundings of
        // 6e-8 against volume changes of a few percent, ~1e-5 again.
        // Measured up to 5.2e-6 (per tet) and 6.3e-6 (nodal) of the largest
        // increment; tolerance 1e-4.
        EXPECT_LT(worst, 1e-4 * scale) << model.npoint() << " points";
      });
}

TEST_P(CpuKernel, ThousandStepTrajectoriesTrackTheDoubleReferenceInEverySceneVariant) {
  // 1000 float steps: rounding of ~6e-8 per step accumulates (and the
  // contact amplifies it). Measured 1.2e-7 to 5.5e-7 of the
  // box edge (6-27 nm on 5 cm) with the per-tet term, 1.9e-7 to 5.3e-7
  // with the nodal term; tolerance 1e-5 of it (0.5 um, against
  // deformations of 0.8-27 mm here). The reaction sums the same per-point
  // terms: measured up to 1.6e-6 relative (per tet) and 3.3e-6 (nodal);
  // tolerance 1e-4.
  for (VolumeTerm volume : testing::kEveryTerm)
    testing::expect_scenes_track_the_reference(fast(), 1e-5 * kSize, 1e-4, volume);
}

TEST_P(CpuKernel, TwoThreadsGiveBitIdenticalResultsToOne) {
  testing::expect_two_threads_bit_identical_to_one(fast());
}

TEST_P(CpuKernel, RestStateStaysPutWithoutGravity) {
  testing::expect_rest_state_stays_put(fast());
}

TEST_P(CpuKernel, KeepsTrackingTheReferenceAfterACut) {
  // As for the trajectories above (600 steps; measured 6.3e-8 m per tet,
  // 3.3e-8 m nodal, against sides 2 cm apart).
  testing::expect_cut_run_tracks_the_reference(fast(), 1e-5 * kSize);
}

TEST(CpuKernelChoice, TheKernelRunsEveryModelItSupportsAndRefusesTheRestByName) {
  const Model wide = random_model(1, 3, VolumeTerm::PerTet, true);
  const Model nodal = random_model(1, 3, VolumeTerm::Nodal, true);
  const Model narrow = random_model(1, 3, VolumeTerm::PerTet, true, 2);  // chunks of 2: no target has 2 float lanes
  const SimdTarget best = simd_targets_supported().front();
  EXPECT_NE(simd_kernel_unsupported(make_step_plan(narrow, {}), narrow.layout.chunk_size, best), "");
  EXPECT_EQ(simd_kernel_unsupported(make_step_plan(wide, {}), wide.layout.chunk_size, best), "");
  EXPECT_EQ(simd_kernel_unsupported(make_step_plan(nodal, {}), nodal.layout.chunk_size, best), "");

  // A layout it cannot run, by default or asked for by name: an error naming
  // why, never a quiet fallback.
  for (const CpuBackendOptions& options : {CpuBackendOptions{Precision::Float, 1},
                                           testing::fast_kernel(best.name, Precision::Double)}) {
    try {
      make_cpu_backend(narrow, {}, options);
      ADD_FAILURE() << "a layout of chunks of 2 must be refused";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Backend);
      EXPECT_NE(std::string(e.what()).find("chunk size 2"), std::string::npos) << e.what();
    }
  }
  for (const Model* model : {&wide, &nodal}) {
    const std::string auto_float = make_cpu_backend(*model, {}, {Precision::Float, 1})->device();
    EXPECT_NE(auto_float.find("simd (" + best.name + ") kernel"), std::string::npos) << auto_float;
  }
  // The plan says what the nodal term's extra passes are, and on which kernel.
  const Plan plan = make_cpu_backend(nodal, {}, testing::fast_kernel(best.name, Precision::Float))->plan();
  ASSERT_EQ(plan.passes[0].name, "nodal-pressure");
  EXPECT_NE(plan.passes[0].detail.find("simd (" + best.name + ") kernel"), std::string::npos) << plan.passes[0].detail;
}

TEST(CpuKernelChoice, APlanWithAPassTheKernelDoesNotRunIsRefusedByName) {
  const Model model = random_model(1, 3, VolumeTerm::PerTet, true);
  const SimdTarget best = simd_targets_supported().front();
  StepPlan plan = make_step_plan(model, {});
  ASSERT_EQ(simd_kernel_unsupported(plan, model.layout.chunk_size, best), "");
  // A shear element pass on a model whose term is the volume term.
  plan.passes.insert(plan.passes.begin() + 1, Pass::ShearElement);
  EXPECT_NE(simd_kernel_unsupported(plan, model.layout.chunk_size, best).find("shear-element"), std::string::npos);
  // A plan without the pass its gravity needs.
  plan = make_step_plan(model, {});
  plan.passes.erase(std::find(plan.passes.begin(), plan.passes.end(), Pass::Gravity));
  EXPECT_NE(simd_kernel_unsupported(plan, model.layout.chunk_size, best).find("gravity"), std::string::npos);
}

TEST(CpuKernelChoice, ThreadCountIsChosenByTimingAndReported) {
  const Model model = random_model(2, 3, VolumeTerm::PerTet, true);
  const std::string device = make_cpu_backend(model, {}, {Precision::Float, 0})->device();
  // With one hardware thread there is nothing to choose.
  if (omp_get_max_threads() > 1) {
    EXPECT_NE(device.find("timed:"), std::string::npos) << device;
  }
  EXPECT_EQ(make_cpu_backend(model, {}, {Precision::Float, 2})->device().find("timed:"), std::string::npos);
}

}  // namespace
}  // namespace cpu_kernel_test
}  // namespace organsim
