// A tick allocates nothing once the backend's vectors are sized: an
// implicit Euler step (core/sim/reference_backend.cpp) and the CPU
// backend's simd kernel on one and two threads. A haptic tick must not
// wait on the allocator. Counted by this test binary's own malloc, calloc, realloc and
// aligned allocations, which forward to glibc's (__libc_*) and count while
// a step runs; operator new and Eigen's vectors allocate through them.
// Not under AddressSanitizer, which owns malloc itself.
#include <gtest/gtest.h>

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "core/sim/cpu_backend.h"
#include "core/sim/reference_backend.h"
#include "tests/core/test_models.h"

#if defined(__SANITIZE_ADDRESS__)
#define ORGANSIM_COUNT_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ORGANSIM_COUNT_ALLOCATIONS 0
#endif
#endif
#ifndef ORGANSIM_COUNT_ALLOCATIONS
#define ORGANSIM_COUNT_ALLOCATIONS 1
#endif

#if ORGANSIM_COUNT_ALLOCATIONS
namespace {
std::atomic<bool> counting{false};
std::atomic<int64_t> allocations{0};
void count() {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
void* malloc(size_t n) {
  count();
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t size) {
  count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, size_t n) {
  count();
  return __libc_realloc(p, n);
}
void* aligned_alloc(size_t alignment, size_t n) {
  count();
  return __libc_memalign(alignment, n);
}
void* memalign(size_t alignment, size_t n) {
  count();
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, size_t alignment, size_t n) {
  count();
  *out = __libc_memalign(alignment, n);
  return *out ? 0 : 12;  // ENOMEM
}
}
#endif

namespace organsim {
namespace tick_allocation_test {
namespace {

#if ORGANSIM_COUNT_ALLOCATIONS
// The 4 cm box at nu 0.45 (springs and the nodal volume term), base held,
// under gravity, and a request that puts a 2 cm sphere 3 mm into its top.
Model pressed_box() {
  Material material;
  material.density = 1000;
  material.young_modulus = 5000;
  material.poisson_ratio = 0.45;
  material.spring_damping_time = 0.002;
  return build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 3, 3, 3), material,
                     testing::fixed_bottom_options(Vec3(0, 0, -9.81)));
}
TickRequest pressing(double dt, int substeps) {
  TickRequest request;
  request.dt = dt;
  request.substeps = substeps;
  request.tool_active = true;
  request.tool_from = request.tool_to = Vec3(0.02, 0.02, 0.04 + 0.02 - 0.003);
  return request;
}

// Allocations in 20 ticks after 5 that size everything; the last tick's
// contacts must be many (the surface contact's pass is in what is counted).
int64_t allocations_in_ticks(Backend& backend, const TickRequest& request) {
  for (int i = 0; i < 5; ++i) backend.tick(request);
  allocations = 0;
  counting = true;
  Reaction reaction;
  for (int i = 0; i < 20; ++i) reaction = backend.tick(request);
  counting = false;
  EXPECT_GT(reaction.contacts, 0) << "the sphere touches the box";
  return allocations.load();
}
#endif

TEST(CpuBackend, ATickAllocatesNothingOnceSizedOnOneThreadAndTwo) {
#if !ORGANSIM_COUNT_ALLOCATIONS
  GTEST_SKIP() << "AddressSanitizer owns malloc: allocations are not counted under it";
#else
  const Model model = pressed_box();
  for (Precision precision : {Precision::Float, Precision::Double})
    for (int threads : {1, 2}) {
      SCOPED_TRACE(std::to_string(threads) + " threads, " + (precision == Precision::Float ? "float" : "double"));
      CpuBackendOptions options;
      options.precision = precision;
      options.threads = threads;
      auto backend = make_cpu_backend(model, {true, ToolMode::Push, 0.02, 500}, options);
      EXPECT_EQ(allocations_in_ticks(*backend, pressing(1e-4, 10)), 0);
    }
#endif
}

TEST(ImplicitEuler, AStepAllocatesNothingOnceSizedWithOrWithoutNewtonIterations) {
#if !ORGANSIM_COUNT_ALLOCATIONS
  GTEST_SKIP() << "AddressSanitizer owns malloc: allocations are not counted under it";
#else
  // Contact blocks in the system, every preconditioner, one linearised
  // solve per step and three Newton iterations (their line search included).
  const Model model = pressed_box();
  for (const int32_t threads : {1, 2})
    for (const int32_t newton : {1, 3})
      for (Preconditioner preconditioner :
           {Preconditioner::BlockJacobi, Preconditioner::TwoLevel, Preconditioner::RestCholesky}) {
        SCOPED_TRACE(std::string(preconditioner_name(preconditioner)) + ", threads " + std::to_string(threads) +
                     ", newton_iterations " + std::to_string(newton));
        ImplicitOptions options;
        options.preconditioner = preconditioner;
        options.newton_iterations = newton;
        auto backend = make_reference_backend(model, {true, ToolMode::Push, 0.02, 500}, Integrator::ImplicitEuler,
                                              options, threads);
        EXPECT_EQ(allocations_in_ticks(*backend, pressing(1e-3, 1)), 0);
        EXPECT_GE(backend->integrator_stats()->cg_iterations.back(), newton);
        EXPECT_EQ(backend->integrator_stats()->last_newton_residuals.size(), newton > 1 ? size_t(newton) : 0);
      }
#endif
}

}  // namespace
}  // namespace tick_allocation_test
}  // namespace organsim
