// AVX2 stepping of LaneRng (x86-64 GCC/Clang only): two vectors of four xoshiro256++ lanes. Include
// only from code that checks the CPU at run time; every function here needs
// FAULTLINE_TARGET("avx2") on its caller.
#pragma once

#include "common/simd.hpp"

#if FAULTLINE_X86_SIMD
#include "rng/lane_rng.hpp"

namespace faultline::rng::avx2 {

// Lanes 0-3 (half 0) or 4-7 (half 1) of a LaneRng.
struct Xoshiro4 {
  __m256i s0, s1, s2, s3;
};

FAULTLINE_TARGET("avx2") inline Xoshiro4 load_half(const LaneRng& rng, int half) {
  return {_mm256_load_si256(reinterpret_cast<const __m256i*>(&rng.s[0][4 * half])),
          _mm256_load_si256(reinterpret_cast<const __m256i*>(&rng.s[1][4 * half])),
          _mm256_load_si256(reinterpret_cast<const __m256i*>(&rng.s[2][4 * half])),
          _mm256_load_si256(reinterpret_cast<const __m256i*>(&rng.s[3][4 * half]))};
}

FAULTLINE_TARGET("avx2") inline void store_half(const Xoshiro4& g, LaneRng& rng, int half) {
  _mm256_store_si256(reinterpret_cast<__m256i*>(&rng.s[0][4 * half]), g.s0);
  _mm256_store_si256(reinterpret_cast<__m256i*>(&rng.s[1][4 * half]), g.s1);
  _mm256_store_si256(reinterpret_cast<__m256i*>(&rng.s[2][4 * half]), g.s2);
  _mm256_store_si256(reinterpret_cast<__m256i*>(&rng.s[3][4 * half]), g.s3);
}

FAULTLINE_TARGET("avx2") inline __m256i rotl64(__m256i x, int k) {
  return _mm256_or_si256(_mm256_slli_epi64(x, k), _mm256_srli_epi64(x, 64 - k));
}

// One step of four lanes: 8 32-bit values (low half of lane 0, high half of lane 0, low half of
// lane 1, ...).
FAULTLINE_TARGET("avx2") inline __m256i step(Xoshiro4& g) {
  const __m256i result = _mm256_add_epi64(rotl64(_mm256_add_epi64(g.s0, g.s3), 23), g.s0);
  const __m256i t = _mm256_slli_epi64(g.s1, 17);
  g.s2 = _mm256_xor_si256(g.s2, g.s0);
  g.s3 = _mm256_xor_si256(g.s3, g.s1);
  g.s1 = _mm256_xor_si256(g.s1, g.s2);
  g.s0 = _mm256_xor_si256(g.s0, g.s3);
  g.s2 = _mm256_xor_si256(g.s2, t);
  g.s3 = rotl64(g.s3, 45);
  return result;
}

}  // namespace faultline::rng::avx2

#endif
