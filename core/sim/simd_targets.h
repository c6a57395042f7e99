#pragma once
// The instruction sets organsim's Highway sources (cpu_kernel_simd.cpp,
// implicit_gather_simd.cpp) are compiled for, included by each before
// hwy/foreach_target.h so that all of them hold the same targets.
//
// The x86-64 baseline's EMU128, SSE4 (x86-64-v2), AVX2 (x86-64-v3), AVX3
// (AVX-512, x86-64-v4); NEON on arm64. Others are left out: each target
// compiles every source once more, and these cover every CPU people run it
// on (AVX3_DL adds nothing the kernels use; SVE and RVV have no fixed
// register width, which the packing needs).
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SSSE3 | HWY_AVX3_DL | HWY_SVE | HWY_SVE2 | HWY_SVE_256 | HWY_SVE2_128 | HWY_RVV)
#endif
// Every attainable target, below the build's baseline too: the portable
// fallback is then compiled on arm64 as well (whose baseline, NEON, would
// otherwise drop it), so that the tests run it wherever they run.
#define HWY_COMPILE_ALL_ATTAINABLE
#include "hwy/detect_targets.h"

// F(target bit, its namespace) for every target compiled here, best first:
// the dispatch tables of the sources' HWY_ONCE parts.
#if HWY_TARGETS & HWY_AVX3
#define ORGANSIM_TARGET_AVX3(F) F(HWY_AVX3, N_AVX3)
#else
#define ORGANSIM_TARGET_AVX3(F)
#endif
#if HWY_TARGETS & HWY_AVX2
#define ORGANSIM_TARGET_AVX2(F) F(HWY_AVX2, N_AVX2)
#else
#define ORGANSIM_TARGET_AVX2(F)
#endif
#if HWY_TARGETS & HWY_SSE4
#define ORGANSIM_TARGET_SSE4(F) F(HWY_SSE4, N_SSE4)
#else
#define ORGANSIM_TARGET_SSE4(F)
#endif
#if HWY_TARGETS & HWY_NEON
#define ORGANSIM_TARGET_NEON(F) F(HWY_NEON, N_NEON)
#else
#define ORGANSIM_TARGET_NEON(F)
#endif
#if HWY_TARGETS & HWY_EMU128
#define ORGANSIM_TARGET_EMU128(F) F(HWY_EMU128, N_EMU128)
#else
#define ORGANSIM_TARGET_EMU128(F)
#endif
#if HWY_TARGETS & HWY_SCALAR
#define ORGANSIM_TARGET_SCALAR(F) F(HWY_SCALAR, N_SCALAR)
#else
#define ORGANSIM_TARGET_SCALAR(F)
#endif
// clang-format off
#define ORGANSIM_COMPILED_TARGETS(F)                                                               \
  ORGANSIM_TARGET_AVX3(F) ORGANSIM_TARGET_AVX2(F) ORGANSIM_TARGET_SSE4(F) ORGANSIM_TARGET_NEON(F) \
  ORGANSIM_TARGET_EMU128(F) ORGANSIM_TARGET_SCALAR(F)
// clang-format on
