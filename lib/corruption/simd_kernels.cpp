// target_clones picks the AVX2 body at load time where the CPU has it; the default body keeps the binary portable.
#include "corruption/simd_kernels.hpp"

#include <algorithm>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define FAULTLINE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FAULTLINE_CLONES
#endif

namespace faultline::corruption::simd {

FAULTLINE_CLONES void axpy(double* acc, const std::uint8_t* src, double k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * static_cast<double>(src[j]);
}

FAULTLINE_CLONES void axpy(double* acc, const double* src, double k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * src[j];
}

FAULTLINE_CLONES void axpy(float* acc, const std::uint8_t* src, float k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * static_cast<float>(src[j]);
}

FAULTLINE_CLONES void axpy(float* acc, const float* src, float k, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) acc[j] += k * src[j];
}

namespace {

// acc[j] for whole blocks of 64 outputs; returns how many outputs it wrote. The running sums stay in registers
// across all taps instead of streaming the accumulator row through memory once per tap.
#if defined(__GNUC__) && defined(__x86_64__)
__attribute__((target("avx2"))) std::size_t weighted_rows_avx2(float* acc, const std::uint8_t* const* rows,
                                                               const float* weights, int taps, std::size_t n) {
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
        a[v] = _mm256_add_ps(a[v], _mm256_mul_ps(k, x));  // product rounded before the add, like the scalar tail
      }
    }
    for (int v = 0; v < 8; ++v) _mm256_storeu_ps(acc + j0 + 8 * v, a[v]);
  }
  return j0;
}

// Same for float sources (the fast snow layer).
__attribute__((target("avx2"))) std::size_t weighted_rows_avx2(float* acc, const float* const* rows,
                                                               const float* weights, int taps, std::size_t n) {
  constexpr std::size_t kBlock = 64;
  std::size_t j0 = 0;
  for (; j0 + kBlock <= n; j0 += kBlock) {
    __m256 a[8];
    for (auto& v : a) v = _mm256_setzero_ps();
    for (int i = 0; i < taps; ++i) {
      const float* r = rows[i] + j0;
      const __m256 k = _mm256_set1_ps(weights[i]);
      for (int v = 0; v < 8; ++v) a[v] = _mm256_add_ps(a[v], _mm256_mul_ps(k, _mm256_loadu_ps(r + 8 * v)));
    }
    for (int v = 0; v < 8; ++v) _mm256_storeu_ps(acc + j0 + 8 * v, a[v]);
  }
  return j0;
}

bool have_avx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}
#endif

}  // namespace

void weighted_rows(float* acc, const std::uint8_t* const* rows, const float* weights, int taps, std::size_t n) {
  std::size_t j0 = 0;
#if defined(__GNUC__) && defined(__x86_64__)
  if (have_avx2()) j0 = weighted_rows_avx2(acc, rows, weights, taps, n);
#endif
  for (std::size_t j = j0; j < n; ++j) {
    float a = 0.0f;
    for (int i = 0; i < taps; ++i) a += weights[i] * static_cast<float>(rows[i][j]);
    acc[j] = a;
  }
}

void weighted_rows(float* acc, const float* const* rows, const float* weights, int taps, std::size_t n) {
  std::size_t j0 = 0;
#if defined(__GNUC__) && defined(__x86_64__)
  if (have_avx2()) j0 = weighted_rows_avx2(acc, rows, weights, taps, n);
#endif
  for (std::size_t j = j0; j < n; ++j) {
    float a = 0.0f;
    for (int i = 0; i < taps; ++i) a += weights[i] * rows[i][j];
    acc[j] = a;
  }
}

FAULTLINE_CLONES std::size_t truncate_outside_band(const float* acc, float band, std::uint8_t* dst,
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
