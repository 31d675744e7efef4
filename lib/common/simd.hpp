// Vector-path selection, in one place. Compile time: whether the x86-64 vector kernels are built at
// all (FAULTLINE_X86_SIMD), and the attributes that build one function for a wider ISA than the
// baseline. Run time: common::cpu_has_* (cpu_features.hpp) says whether this CPU, and
// FAULTLINE_SCALAR, let such a function be called. A hand-dispatched kernel pairs the two:
//   #if FAULTLINE_X86_SIMD
//   FAULTLINE_TARGET("avx2") std::size_t fill_avx2(...);   // returns how far it got
//   #endif
//   ...
//   #if FAULTLINE_X86_SIMD
//   if (common::cpu_has_avx2()) done = fill_avx2(...);
//   #endif
//   (the portable loop finishes from `done`, with the same arithmetic and rounding)
#pragma once

#include "common/cpu_features.hpp"

#if defined(__GNUC__) && defined(__x86_64__)
#define FAULTLINE_X86_SIMD 1
#include <immintrin.h>
// Builds the function for `isa` ("avx2", "avx2,fma", ...); call it only where the matching
// cpu_has_* is true.
#define FAULTLINE_TARGET(isa) __attribute__((target(isa)))
// The same, always inlined into a FAULTLINE_TARGET caller of that ISA: helpers and lambdas inside
// vector kernels.
#define FAULTLINE_TARGET_INLINE(isa) __attribute__((target(isa), always_inline))
#else
#define FAULTLINE_X86_SIMD 0
#endif

// One body built for `isa` and for the baseline, picked by the loader from the CPU (GCC only;
// FAULTLINE_SCALAR does not reach it, and both builds are the same source). Elsewhere the baseline
// build alone.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define FAULTLINE_CLONES(isa) __attribute__((target_clones(isa, "default")))
#else
#define FAULTLINE_CLONES(isa)
#endif
