// How many vector instructions of each kind one core retires per cycle,
// measured with 12 independent chains each (so latency does not limit it).
// It answers whether a machine runs 512-bit instructions at full width or
// as two 256-bit halves, which decides how fast the simd kernel's AVX3 target can be
// (docs/bench.md, "Looking inside the step"). Build and run (one core, idle):
//
//   g++ -O2 -march=native scripts/simd_throughput.cpp -o /tmp/simd && /tmp/simd
//
// The cycle count comes from a dependent chain of scalar adds (one per
// cycle on every x86 core since the 1990s), so no counter access is needed.
// GCC 12 fills unused intrinsic operands with undefined values and warns
// about them at every inlined use (a known false positive).
#pragma GCC diagnostic ignored "-Wuninitialized"
#include <immintrin.h>

#include <chrono>
#include <cstdio>

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Cycles per second: a chain of dependent integer adds runs at one per cycle.
// The fastest of several short runs, so that another process taking the
// core for a moment does not lower it.
double clock_hz() {
  constexpr long kAdds = 200'000'000;
  double best = 0;
  for (int run = 0; run < 7; ++run) {
    long x = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (long i = 0; i < kAdds; ++i) asm volatile("add $1, %0" : "+r"(x));
    const double hz = kAdds / seconds_since(t0);
    if (hz > best) best = hz;
  }
  return best;
}

template <typename T, typename Op>
double per_cycle(double hz, T (*set1)(float), Op op) {
  constexpr long kIter = 100'000'000;
  // Twelve named chains: an array would live in memory.
  T a0 = set1(1), a1 = set1(2), a2 = set1(3), a3 = set1(4), a4 = set1(5), a5 = set1(6);
  T a6 = set1(7), a7 = set1(8), a8 = set1(9), a9 = set1(10), a10 = set1(11), a11 = set1(12);
  const T m = set1(0.5f);
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < kIter; ++i) {
    a0 = op(a0, m), a1 = op(a1, m), a2 = op(a2, m), a3 = op(a3, m), a4 = op(a4, m), a5 = op(a5, m);
    a6 = op(a6, m), a7 = op(a7, m), a8 = op(a8, m), a9 = op(a9, m), a10 = op(a10, m), a11 = op(a11, m);
    // Keep every chain alive and in a register.
    asm volatile("" : "+v"(a0), "+v"(a1), "+v"(a2), "+v"(a3), "+v"(a4), "+v"(a5));
    asm volatile("" : "+v"(a6), "+v"(a7), "+v"(a8), "+v"(a9), "+v"(a10), "+v"(a11));
  }
  return kIter * 12 / seconds_since(t0) / hz;
}

__m512 set512(float v) { return _mm512_set1_ps(v); }
__m256 set256(float v) { return _mm256_set1_ps(v); }

}  // namespace

int main() {
  const double hz = clock_hz();
  std::printf("clock: %.2f GHz (dependent adds)\n", hz / 1e9);
  std::printf("instructions per cycle, 12 independent chains:\n");
  auto row = [](const char* name, double r) { std::printf("  %-30s %.2f\n", name, r); };
  row("512-bit FMA", per_cycle<__m512>(hz, set512, [](__m512 a, __m512 m) { return _mm512_fmadd_ps(a, m, m); }));
  row("256-bit FMA", per_cycle<__m256>(hz, set256, [](__m256 a, __m256 m) { return _mm256_fmadd_ps(a, m, m); }));
  row("512-bit add", per_cycle<__m512>(hz, set512, [](__m512 a, __m512 m) { return _mm512_add_ps(a, m); }));
  row("512-bit unpacklo", per_cycle<__m512>(hz, set512, [](__m512 a, __m512 m) { return _mm512_unpacklo_ps(a, m); }));
  row("256-bit unpacklo", per_cycle<__m256>(hz, set256, [](__m256 a, __m256 m) { return _mm256_unpacklo_ps(a, m); }));
  row("512-bit shuffle_f32x4", per_cycle<__m512>(hz, set512, [](__m512 a, __m512 m) {
        return _mm512_shuffle_f32x4(a, m, 0x44);
      }));
  row("512-bit insertf32x4", per_cycle<__m512>(hz, set512, [](__m512 a, __m512 m) {
        return _mm512_insertf32x4(a, _mm512_castps512_ps128(m), 1);
      }));
  row("256-bit insertf128", per_cycle<__m256>(hz, set256, [](__m256 a, __m256 m) {
        return _mm256_insertf128_ps(a, _mm256_castps256_ps128(m), 1);
      }));
  std::printf("peak single precision, one core: %.0f GFLOP/s (512-bit FMA rate x 32)\n",
              per_cycle<__m512>(hz, set512, [](__m512 a, __m512 m) { return _mm512_fmadd_ps(a, m, m); }) * 32 *
                  hz / 1e9);
  return 0;
}
