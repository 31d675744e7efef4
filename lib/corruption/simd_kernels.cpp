// target_clones picks the AVX2 body at load time where the CPU has it; the default body keeps the
// binary portable.
#include "corruption/simd_kernels.hpp"

#include <algorithm>
#include <cmath>

#include "common/simd.hpp"

namespace faultline::corruption::simd {

FAULTLINE_CLONES("avx2") void axpy(double* acc, const std::uint8_t* src, double k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * static_cast<double>(src[j]);
}

FAULTLINE_CLONES("avx2") void axpy(double* acc, const double* src, double k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * src[j];
}

FAULTLINE_CLONES("avx2") void axpy(float* acc, const std::uint8_t* src, float k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * static_cast<float>(src[j]);
}

FAULTLINE_CLONES("avx2") void axpy(float* acc, const float* src, float k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * src[j];
}

namespace {

// acc[j] for whole blocks of 64 outputs; returns how many outputs it wrote. The running sums stay
// in registers across all taps instead of streaming the accumulator row through memory once per
// tap.
#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET("avx2")
std::size_t weighted_rows_avx2(float* acc, const std::uint8_t* const* rows, const float* weights,
                               int taps, std::size_t n) {
  constexpr std::size_t kBlock = 64;
  std::size_t j0 = 0;
  for (; j0 + kBlock <= n; j0 += kBlock) {
    __m256 a[8];
    for (auto& v : a) v = _mm256_setzero_ps();
    for (int i = 0; i < taps; ++i) {
      const std::uint8_t* r = rows[i] + j0;
      const __m256 k = _mm256_set1_ps(weights[i]);
      for (int v = 0; v < 8; ++v) {
        const __m128i bytes = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(r + 8 * v));
        const __m256 x = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes));
        a[v] = _mm256_add_ps(
            a[v], _mm256_mul_ps(k, x));  // product rounded before the add, like the scalar tail
      }
    }
    for (int v = 0; v < 8; ++v) _mm256_storeu_ps(acc + j0 + 8 * v, a[v]);
  }
  return j0;
}

// Same for float sources (the fast snow layer, fast mode only), with fused multiply-adds.
FAULTLINE_TARGET("avx2,fma")
std::size_t weighted_rows_avx2(float* acc, const float* const* rows, const float* weights, int taps,
                               std::size_t n) {
  constexpr std::size_t kBlock = 64;
  std::size_t j0 = 0;
  for (; j0 + kBlock <= n; j0 += kBlock) {
    __m256 a[8];
    for (auto& v : a) v = _mm256_setzero_ps();
    for (int i = 0; i < taps; ++i) {
      const float* r = rows[i] + j0;
      const __m256 k = _mm256_set1_ps(weights[i]);
      for (int v = 0; v < 8; ++v) a[v] = _mm256_fmadd_ps(k, _mm256_loadu_ps(r + 8 * v), a[v]);
    }
    for (int v = 0; v < 8; ++v) _mm256_storeu_ps(acc + j0 + 8 * v, a[v]);
  }
  return j0;
}

// 64 outputs per block kept in registers across all taps (fused multiply-add over half-precision
// source rows: integers 0..255 are exact in binary16, and half the bytes per load of float32 rows,
// measured ~1.5x faster), then the band test and truncation on the registers (no accumulator row
// written or re-read). eq[c] = lanes j0 + 16c .. j0 + 16c + 15 (as 16-bit masks) whose taps all
// hold the first tap's value.
FAULTLINE_TARGET("avx2")
inline void flat_lanes(const std::uint16_t* const* rows, int taps, std::size_t j0, __m256i* eq) {
  for (int c = 0; c < 4; ++c) {
    const __m256i first =
        _mm256_loadu_si256(reinterpret_cast<const __m256i*>(rows[0] + j0 + 16 * c));
    eq[c] = _mm256_set1_epi16(-1);
    for (int i = 1; i < taps; ++i) {
      const __m256i x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(rows[i] + j0 + 16 * c));
      eq[c] = _mm256_and_si256(eq[c], _mm256_cmpeq_epi16(x, first));
    }
  }
}

// Eight half-precision byte values as int32.
FAULTLINE_TARGET("avx2,f16c") inline __m256i first_bytes(const std::uint16_t* halves) {
  return _mm256_cvttps_epi32(
      _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(halves))));
}

// Stores 64 results (clamped to 0..255) and their ambiguity mask (bit k: lane k); counts the
// ambiguous ones.
FAULTLINE_TARGET("avx2")
inline void store_truncated(const __m256i* lo, const __m256i* badm, std::uint8_t* dst,
                            std::uint64_t* ambiguous, std::size_t& bad_total) {
  const __m256i max255 = _mm256_set1_epi32(255);
  std::uint64_t mask = 0;
  for (int v = 0; v < 8; v += 2) {
    __m256i q[2];
    for (int h = 0; h < 2; ++h)
      q[h] = _mm256_min_epi32(_mm256_max_epi32(lo[v + h], _mm256_setzero_si256()), max255);
    const __m256i w16 = _mm256_permute4x64_epi64(_mm256_packus_epi32(q[0], q[1]), 0xD8);
    const __m128i b8 =
        _mm_packus_epi16(_mm256_castsi256_si128(w16), _mm256_extracti128_si256(w16, 1));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + 8 * v), b8);
    const __m256i m16 = _mm256_permute4x64_epi64(_mm256_packs_epi32(badm[v], badm[v + 1]), 0xD8);
    const __m128i m8 =
        _mm_packs_epi16(_mm256_castsi256_si128(m16), _mm256_extracti128_si256(m16, 1));
    mask |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm_movemask_epi8(m8))) << (8 * v);
  }
  *ambiguous = mask;
  bad_total += static_cast<std::size_t>(__builtin_popcountll(mask));
}

FAULTLINE_TARGET("avx2,fma,f16c")
std::size_t weighted_rows_truncate_f16_avx2(const std::uint16_t* const* rows, const float* weights,
                                            const double* weights64, int taps, float band,
                                            const std::int32_t* flat, std::uint8_t* dst,
                                            std::uint64_t* ambiguous, std::size_t n,
                                            std::size_t* count) {
  constexpr std::size_t kBlock = 64;
  const __m256 vband = _mm256_set1_ps(band);
  const __m256 zero = _mm256_setzero_ps();
  std::size_t j0 = 0, bad_total = 0;
  // Wholly flat stretches are the caller's (motion blur fills them without sums); the blocks here
  // are mixed.
  for (; j0 + kBlock <= n; j0 += kBlock) {
    __m256i eq[4];  // eq[c]: lanes j0 + 16c .. + 15 whose taps all equal the first tap's byte
    __m256i lo[8], badm[8];
    __m256 a[8];
    for (auto& v : a) v = _mm256_setzero_ps();
    for (int i = 0; i < taps; ++i) {
      const std::uint16_t* r = rows[i] + j0;
      const __m256 k = _mm256_set1_ps(weights[i]);
      for (int v = 0; v < 8; ++v) {
        const __m256 x =
            _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r + 8 * v)));
        a[v] = _mm256_fmadd_ps(k, x, a[v]);
      }
    }
    int bad_lanes = 0;
    for (int v = 0; v < 8; ++v) {
      const __m256 lo_f = _mm256_sub_ps(a[v], vband);
      lo[v] = _mm256_cvttps_epi32(lo_f);
      const __m256i hi = _mm256_cvttps_epi32(_mm256_add_ps(a[v], vband));
      const __m256i neq = _mm256_xor_si256(_mm256_cmpeq_epi32(lo[v], hi), _mm256_set1_epi32(-1));
      const __m256i neg = _mm256_castps_si256(_mm256_cmp_ps(lo_f, zero, _CMP_LT_OQ));
      badm[v] = _mm256_or_si256(neq, neg);
      bad_lanes += __builtin_popcount(
          static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(badm[v]))));
    }
    // Flat neighbourhoods (every tap the same byte) sit exactly on the band. Where a block has
    // several ambiguous values, they are almost always flat (synthetic and overexposed frames are
    // full of them): resolve those here, 16 lanes per compare, from the table of exact flat
    // results, instead of one by one in the caller.
    if (flat != nullptr && bad_lanes >= 4) {
      flat_lanes(rows, taps, j0, eq);
      for (int v = 0; v < 8; ++v) {
        const __m256i e = eq[v / 2];
        const __m256i flat_lane = _mm256_cvtepi16_epi32(
            v % 2 == 0 ? _mm256_castsi256_si128(e) : _mm256_extracti128_si256(e, 1));
        const __m256i use = _mm256_and_si256(flat_lane, badm[v]);
        if (_mm256_testz_si256(use, use)) continue;
        lo[v] = _mm256_mask_i32gather_epi32(lo[v], flat, first_bytes(rows[0] + j0 + 8 * v), use, 4);
        badm[v] = _mm256_andnot_si256(use, badm[v]);
      }
    }
    // Values still ambiguous (near-flat: taps that differ only where the weight is ~1e-8 move the
    // float64 sum across the integer) get the exact float64 sum here, 4 lanes at a time in the
    // reference's order (product rounded, then added; this file is built without contraction), when
    // there are enough of them to beat the caller's one-by-one path.
    if (weights64 != nullptr) {
      for (int v = 0; v < 8; ++v) {
        const int m = _mm256_movemask_ps(_mm256_castsi256_ps(badm[v]));
        if (__builtin_popcount(static_cast<unsigned>(m)) < 2) continue;
        // Both halves at once: two independent add chains (the chain's latency, not the arithmetic,
        // is the cost).
        __m256d acc[2] = {_mm256_setzero_pd(), _mm256_setzero_pd()};
        for (int i = 0; i < taps; ++i) {
          const __m256 x8 = _mm256_cvtph_ps(
              _mm_loadu_si128(reinterpret_cast<const __m128i*>(rows[i] + j0 + 8 * v)));
          const __m256d k = _mm256_set1_pd(weights64[i]);
          acc[0] =
              _mm256_add_pd(acc[0], _mm256_mul_pd(k, _mm256_cvtps_pd(_mm256_castps256_ps128(x8))));
          acc[1] = _mm256_add_pd(acc[1],
                                 _mm256_mul_pd(k, _mm256_cvtps_pd(_mm256_extractf128_ps(x8, 1))));
        }
        __m128i part[2];
        for (int h = 0; h < 2; ++h) {
          const __m256d c =
              _mm256_min_pd(_mm256_max_pd(acc[h], _mm256_setzero_pd()), _mm256_set1_pd(255.0));
          part[h] = _mm256_cvttpd_epi32(c);
        }
        lo[v] = _mm256_set_m128i(part[1], part[0]);
        badm[v] = _mm256_setzero_si256();
      }
    }
    store_truncated(lo, badm, dst + j0, ambiguous + j0 / kBlock, bad_total);
  }
  *count = bad_total;
  return j0;
}

// Fast mode: 8 * V outputs kept in registers across all taps, each fused multiply-add taking its
// float32 row operand straight from memory (no conversion per tap), then truncation by the
// saturating packs. Only vectors with a sum within `band` of an integer go over the taps again.
template <int V>
FAULTLINE_TARGET_INLINE("avx2,fma")
inline void fast_block(const float* const* rows, const float* weights, int taps32,
                       const double* weights64, int taps, float band, const std::int32_t* flat,
                       std::uint8_t* dst, std::size_t j0) {
  __m256 a[V];
  for (auto& v : a) v = _mm256_setzero_ps();
  for (int i = 0; i < taps32; ++i) {
    const float* r = rows[i] + j0;
    // Keeps r as one base register with constant displacements (GCC otherwise holds j0 + 8 v in V
    // registers and spills).
    __asm__("" : "+r"(r));
    const __m256 k = _mm256_broadcast_ss(weights + i);
    for (int v = 0; v < V; ++v) a[v] = _mm256_fmadd_ps(k, _mm256_loadu_ps(r + 8 * v), a[v]);
  }
  const __m256 vband = _mm256_set1_ps(band);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7FFFFFFF));
  __m256i q[V];
  __m256 near[V];
  int near_bits = 0;
  for (int v = 0; v < V; ++v) {
    q[v] = _mm256_cvttps_epi32(a[v]);  // negatives (> -1e-3) truncate to 0; the packs clamp at 255
    const __m256 nearest = _mm256_round_ps(a[v], _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
    near[v] =
        _mm256_cmp_ps(_mm256_and_ps(_mm256_sub_ps(a[v], nearest), abs_mask), vband, _CMP_LT_OQ);
    near_bits |= (_mm256_movemask_ps(near[v]) != 0) << v;
  }
  // Near-integer sums, where float32 may truncate the other way: flat lanes take the tabulated
  // exact result, the others the float64 sum (one pass over the taps for both).
  for (int v = 0; v < V; ++v) {
    if (!(near_bits >> v & 1)) continue;
    const __m256 first = _mm256_loadu_ps(rows[0] + j0 + 8 * v);
    __m256 eq = near[v];
    __m256d sum[2] = {_mm256_setzero_pd(), _mm256_setzero_pd()};
    for (int i = 0; i < taps; ++i) {
      const __m256 x = _mm256_loadu_ps(rows[i] + j0 + 8 * v);
      eq = _mm256_and_ps(eq, _mm256_cmp_ps(x, first, _CMP_EQ_OQ));
      const __m256d k = _mm256_broadcast_sd(weights64 + i);
      sum[0] = _mm256_fmadd_pd(k, _mm256_cvtps_pd(_mm256_castps256_ps128(x)), sum[0]);
      sum[1] = _mm256_fmadd_pd(k, _mm256_cvtps_pd(_mm256_extractf128_ps(x, 1)), sum[1]);
    }
    const __m256i exact =
        _mm256_set_m128i(_mm256_cvttpd_epi32(_mm256_max_pd(sum[1], _mm256_setzero_pd())),
                         _mm256_cvttpd_epi32(_mm256_max_pd(sum[0], _mm256_setzero_pd())));
    q[v] = _mm256_blendv_epi8(q[v], exact, _mm256_castps_si256(near[v]));
    q[v] = _mm256_mask_i32gather_epi32(q[v], flat, _mm256_cvttps_epi32(first),
                                       _mm256_castps_si256(eq), 4);
  }
  const __m256i byte_order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  for (int v = 0; v < V; v += 4) {
    const __m256i w01 = _mm256_packus_epi32(q[v], q[v + 1]);
    const __m256i w23 = _mm256_packus_epi32(q[v + 2], q[v + 3]);
    const __m256i b = _mm256_permutevar8x32_epi32(_mm256_packus_epi16(w01, w23), byte_order);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + j0 + 8 * v), b);
  }
}

// Blocks of 96 outputs (12 accumulators: more independent chains than the FMA latency needs), then
// 64 or 32.
FAULTLINE_TARGET("avx2,fma")
std::size_t weighted_rows_truncate_fast_avx2(const float* const* rows, const float* weights,
                                             int taps32, const double* weights64, int taps,
                                             float band, const std::int32_t* flat,
                                             std::uint8_t* dst, std::size_t n) {
  std::size_t j0 = 0;
  for (; j0 + 96 <= n; j0 += 96)
    fast_block<12>(rows, weights, taps32, weights64, taps, band, flat, dst, j0);
  if (j0 + 64 <= n) {
    fast_block<8>(rows, weights, taps32, weights64, taps, band, flat, dst, j0);
    j0 += 64;
  }
  if (j0 + 32 <= n) {
    fast_block<4>(rows, weights, taps32, weights64, taps, band, flat, dst, j0);
    j0 += 32;
  }
  return j0;
}

FAULTLINE_TARGET("avx2")
void u8_to_float_avx2(const std::uint8_t* src, float* dst, std::size_t n, std::size_t* done) {
  std::size_t j = 0;
  for (; j + 8 <= n; j += 8) {
    const __m128i bytes = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(src + j));
    _mm256_storeu_ps(dst + j, _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes)));
  }
  *done = j;
}

FAULTLINE_TARGET("avx2,f16c")
void u8_to_half_avx2(const std::uint8_t* src, std::uint16_t* dst, std::size_t n,
                     std::size_t* done) {
  std::size_t j = 0;
  for (; j + 8 <= n; j += 8) {
    const __m128i bytes = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(src + j));
    const __m256 x = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + j), _mm256_cvtps_ph(x, 0));
  }
  *done = j;
}

// Words [w_begin, w_end) (each wholly inside n, with p - period >= 0 for every lane): 64 elements
// per word, two 16-lane compares per 32 bits packed to bytes (lane order restored) for movemask.
FAULTLINE_TARGET("avx2")
void period_change_bits_avx2(const std::uint16_t* src, std::size_t period, std::uint64_t* bits,
                             std::size_t w_begin, std::size_t w_end) {
  for (std::size_t w = w_begin; w < w_end; ++w) {
    std::uint64_t word = 0;
    for (int h = 0; h < 2; ++h) {
      const std::uint16_t* p = src + 64 * w + 32 * h;
      __m256i eq[2];
      for (int k = 0; k < 2; ++k) {
        const __m256i x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 16 * k));
        const __m256i y = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 16 * k - period));
        eq[k] = _mm256_cmpeq_epi16(x, y);
      }
      const __m256i packed = _mm256_permute4x64_epi64(_mm256_packs_epi16(eq[0], eq[1]), 0xD8);
      const auto m = static_cast<std::uint32_t>(_mm256_movemask_epi8(packed));
      word |= static_cast<std::uint64_t>(~m) << (32 * h);
    }
    bits[w] = word;
  }
}

// Same for float32 rows: 8 lanes per compare, 8 compares per word.
FAULTLINE_TARGET("avx2")
void period_change_bits_avx2(const float* src, std::size_t period, std::uint64_t* bits,
                             std::size_t w_begin, std::size_t w_end) {
  for (std::size_t w = w_begin; w < w_end; ++w) {
    std::uint64_t word = 0;
    for (int k = 0; k < 8; ++k) {
      const float* p = src + 64 * w + 8 * k;
      const __m256 eq = _mm256_cmp_ps(_mm256_loadu_ps(p), _mm256_loadu_ps(p - period), _CMP_EQ_OQ);
      word |= static_cast<std::uint64_t>(~static_cast<unsigned>(_mm256_movemask_ps(eq)) & 0xFFu)
              << (8 * k);
    }
    bits[w] = word;
  }
}
#endif

}  // namespace

void weighted_rows(float* acc, const std::uint8_t* const* rows, const float* weights, int taps,
                   std::size_t n) {
  std::size_t j0 = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) j0 = weighted_rows_avx2(acc, rows, weights, taps, n);
#endif
  for (std::size_t j = j0; j < n; ++j) {
    float a = 0.0f;
    for (int i = 0; i < taps; ++i) a += weights[i] * static_cast<float>(rows[i][j]);
    acc[j] = a;
  }
}

void weighted_rows(float* acc, const float* const* rows, const float* weights, int taps,
                   std::size_t n) {
  std::size_t j0 = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2_fma()) j0 = weighted_rows_avx2(acc, rows, weights, taps, n);
#endif
  for (std::size_t j = j0; j < n; ++j) {
    float a = 0.0f;
    for (int i = 0; i < taps; ++i) a += weights[i] * rows[i][j];
    acc[j] = a;
  }
}

void u8_to_half(const std::uint8_t* src, std::uint16_t* dst, std::size_t n) {
  std::size_t j = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2_fma_f16c()) u8_to_half_avx2(src, dst, n, &j);
#endif
  for (; j < n; ++j) dst[j] = half_of_byte(src[j]);
}

namespace {

template <typename T>
void period_change_bits_any(const T* src, std::size_t n, std::size_t period, std::uint64_t* bits) {
  const std::size_t words = (n + 63) / 64;
  auto scalar_words = [&](std::size_t w_begin, std::size_t w_end) {
    for (std::size_t w = w_begin; w < w_end; ++w) {
      std::uint64_t word = 0;
      for (std::size_t p = 64 * w; p < std::min(n, 64 * w + 64); ++p) {
        if (p >= period && src[p] != src[p - period]) word |= std::uint64_t{1} << (p - 64 * w);
      }
      bits[w] = word;
    }
  };
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2() && period <= 64 && n >= 128) {
    scalar_words(0, 1);
    period_change_bits_avx2(src, period, bits, 1, n / 64);
    scalar_words(n / 64, words);
    return;
  }
#endif
  scalar_words(0, words);
}

}  // namespace

void period_change_bits(const std::uint16_t* src, std::size_t n, std::size_t period,
                        std::uint64_t* bits) {
  period_change_bits_any(src, n, period, bits);
}

void period_change_bits(const float* src, std::size_t n, std::size_t period, std::uint64_t* bits) {
  period_change_bits_any(src, n, period, bits);
}

void u8_to_float(const std::uint8_t* src, float* dst, std::size_t n) {
  std::size_t j = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) u8_to_float_avx2(src, dst, n, &j);
#endif
  for (; j < n; ++j) dst[j] = static_cast<float>(src[j]);
}

void weighted_rows_truncate_fast(const float* const* rows, const float* weights, int taps32,
                                 const double* weights64, int taps, float band,
                                 const std::int32_t* flat, std::uint8_t* dst, std::size_t n) {
  std::size_t j0 = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2_fma()) {
    j0 = weighted_rows_truncate_fast_avx2(rows, weights, taps32, weights64, taps, band, flat, dst,
                                          n);
  }
#endif
  for (std::size_t j = j0; j < n; ++j) {
    float a = 0.0f;
    for (int i = 0; i < taps32; ++i) a += weights[i] * rows[i][j];
    int v = std::min(std::max(static_cast<int>(a), 0), 255);
    if (std::fabs(a - std::nearbyint(a)) < band) {
      bool all_equal = true;
      double exact = 0.0;
      for (int i = 0; i < taps; ++i) {
        exact += weights64[i] * rows[i][j];
        all_equal = all_equal && rows[i][j] == rows[0][j];
      }
      v = all_equal ? flat[static_cast<int>(rows[0][j])]
                    : static_cast<int>(std::min(std::max(exact, 0.0), 255.0));
    }
    dst[j] = static_cast<std::uint8_t>(v);
  }
}

std::size_t weighted_rows_truncate(const std::uint16_t* const* rows, const float* weights,
                                   const double* weights64, int taps, float band,
                                   const std::int32_t* flat, std::uint8_t* dst,
                                   std::uint64_t* ambiguous, std::size_t n) {
  std::size_t j0 = 0, count = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2_fma_f16c()) {
    j0 = weighted_rows_truncate_f16_avx2(rows, weights, weights64, taps, band, flat, dst, ambiguous,
                                         n, &count);
  }
#endif
  for (std::size_t j = j0; j < n; ++j) {
    if (j % 64 == 0) ambiguous[j / 64] = 0;
    float a = 0.0f;
    for (int i = 0; i < taps; ++i) a += weights[i] * byte_of_half(rows[i][j]);
    const float lo_f = a - band;
    const int lo = static_cast<int>(lo_f);
    const int hi = static_cast<int>(a + band);
    const bool bad = (lo != hi) | (lo_f < 0.0f);
    dst[j] = static_cast<std::uint8_t>(std::min(std::max(lo, 0), 255));
    ambiguous[j / 64] |= static_cast<std::uint64_t>(bad) << (j % 64);
    count += bad;
  }
  return count;
}

FAULTLINE_CLONES("avx2")
std::size_t truncate_outside_band(const float* acc, float band, std::uint8_t* dst,
                                  std::uint8_t* ambiguous, std::size_t n) {
  std::size_t count = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const float lo_f = acc[j] - band;
    // int conversion truncates, which is floor because lo_f >= 0 wherever the result is used.
    const int lo = static_cast<int>(lo_f);
    const int hi = static_cast<int>(acc[j] + band);
    const bool bad = (lo != hi) | (lo_f < 0.0f);
    dst[j] = static_cast<std::uint8_t>(std::min(std::max(lo, 0), 255));
    ambiguous[j] = static_cast<std::uint8_t>(bad);
    count += bad;
  }
  return count;
}

}  // namespace faultline::corruption::simd
