// Which target the simd kernel runs on: the best this CPU has by default,
// a lower one when ORGANSIM_SIMD (or CpuBackendOptions::simd) asks for it,
// named in device(); an unknown or unsupported name is an error naming the
// choices. Highway's mock of the CPU's targets stands in for a CPU with
// only the portable fallback.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <functional>

#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/util/error.h"
#include "tests/core/cpu_kernel_test_util.h"

namespace organsim {
namespace simd_dispatch_test {
namespace {

// ORGANSIM_SIMD and Highway's mock set for one test, undone after it.
class SimdDispatch : public ::testing::Test {
 protected:
  void TearDown() override {
    unsetenv("ORGANSIM_SIMD");
    set_simd_targets_for_test(0);
  }
};

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST_F(SimdDispatch, TheBestSupportedTargetIsTheDefaultAndDeviceNamesIt) {
  unsetenv("ORGANSIM_SIMD");
  const std::vector<SimdTarget> supported = simd_targets_supported();
  ASSERT_FALSE(supported.empty());
  // Best first: the compiled list's order, filtered by the CPU.
  const std::vector<SimdTarget> compiled = simd_targets_compiled();
  EXPECT_EQ(supported.front(), *std::find_first_of(compiled.begin(), compiled.end(), supported.begin(), supported.end()));
  EXPECT_EQ(default_simd_target(), supported.front());
#if defined(__x86_64__) && !defined(__SSE4_1__)
  // The portable build (for the x86-64 baseline) carries the fallback, which
  // runs everywhere and is last, and SSE4, AVX2 and AVX3 (AVX-512).
  EXPECT_TRUE(supported.back().name == "scalar" || supported.back().name == "emu128") << supported.back().name;
  for (const char* name : {"sse4", "avx2", "avx3"})
    EXPECT_NE(std::find_if(compiled.begin(), compiled.end(), [&](const SimdTarget& t) { return t.name == name; }),
              compiled.end())
        << name;
#endif
  const Model model = testing::random_model(1, 3, testing::VolumeTerm::PerTet, true);
  const std::string device = make_cpu_backend(model, {}, {Precision::Float, 1})->device();
  EXPECT_NE(device.find("simd (" + supported.front().name + ") kernel"), std::string::npos) << device;
}

TEST_F(SimdDispatch, ForcingALowerTargetTakesEffectAndIsNamed) {
  const std::vector<SimdTarget> supported = simd_targets_supported();
  const SimdTarget lowest = supported.back();
  setenv("ORGANSIM_SIMD", lowest.name.c_str(), 1);
  EXPECT_EQ(default_simd_target(), lowest);
  const Model model = testing::random_model(1, 3, testing::VolumeTerm::PerTet, true);
  const auto backend = make_cpu_backend(model, {}, {Precision::Double, 1});
  EXPECT_NE(backend->device().find("simd (" + lowest.name + ") kernel"), std::string::npos) << backend->device();
  // The lanes of that target in the plan: one double on the portable scalar target.
  if (lowest.name == "scalar") {
    EXPECT_NE(backend->plan().passes.back().detail.find("1 double lanes"), std::string::npos);
  }
  // "best" is the default's own name.
  setenv("ORGANSIM_SIMD", "best", 1);
  EXPECT_EQ(default_simd_target(), supported.front());
  // The option wins over the variable.
  setenv("ORGANSIM_SIMD", "bogus", 1);
  EXPECT_NE(make_cpu_backend(model, {}, {Precision::Double, 1, lowest.name})->device().find(lowest.name),
            std::string::npos);
}

TEST_F(SimdDispatch, AnUnknownOrUnsupportedTargetIsAClearError) {
  setenv("ORGANSIM_SIMD", "avx9", 1);
  const std::string unknown = error_of([] { default_simd_target(); });
  EXPECT_NE(unknown.find("ORGANSIM_SIMD"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("avx9"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find(simd_targets_compiled().front().name), std::string::npos) << unknown;  // the choices
  const Model model = testing::random_model(1, 3, testing::VolumeTerm::PerTet, true);
  EXPECT_THROW(make_cpu_backend(model, {}, {Precision::Float, 1}), Error);
  unsetenv("ORGANSIM_SIMD");
  // A CPU with only the lowest target compiled in (Highway's mock; in the
  // portable build the fallback): the best is then that one, and any other
  // compiled target is refused by name.
  if (simd_targets_compiled().size() < 2) GTEST_SKIP() << "one target compiled (a -march=native build)";
  const SimdTarget fallback = simd_targets_supported().back();
  set_simd_targets_for_test(fallback.bits);
  ASSERT_EQ(simd_targets_supported().size(), 1u);
  EXPECT_EQ(default_simd_target(), fallback);
  const SimdTarget best = simd_targets_compiled().front();
  ASSERT_NE(best, fallback);
  const std::string unsupported = error_of([&] { simd_target_named(best.name, "--simd"); });
  EXPECT_NE(unsupported.find("cannot run the " + best.name), std::string::npos) << unsupported;
  EXPECT_NE(unsupported.find("--simd"), std::string::npos) << unsupported;
  EXPECT_THROW(make_cpu_backend(model, {}, {Precision::Float, 1, best.name}), Error);
}

}  // namespace
}  // namespace simd_dispatch_test
}  // namespace organsim
