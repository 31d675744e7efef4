// Dark sampling loop: AVX2 body (two 4 x 64-bit xoshiro256++ vectors, 8-wide gathers, branch-free
// select) chosen at run time, scalar body otherwise and for the tail.
#include "corruption/dark_sampler.hpp"

#include <array>
#include <cmath>
#include <utility>

#include "common/simd.hpp"
#include "rng/lane_rng_avx2.hpp"

namespace faultline::corruption {
namespace {

inline std::uint8_t sample(const std::uint32_t* row, std::uint32_t bits) {
  const std::uint32_t bucket = bits >> 24;
  const std::uint32_t u = bits & ((1u << kDarkAliasThresholdBits) - 1u);
  const std::uint32_t e = row[bucket];
  // Branch-free select: the outcome is random, so a branch would mispredict often.
  const std::uint32_t keep = 0u - static_cast<std::uint32_t>(u < (e >> 8));
  return static_cast<std::uint8_t>((bucket & keep) | (e & ~keep));
}

void sample_scalar(const std::uint32_t* tables, int lo, const std::uint8_t* src, std::uint8_t* dst,
                   std::size_t n, rng::LaneRng& rng) {
  std::uint32_t r[rng::LaneRng::kValuesPerStep];
  constexpr std::size_t kStep = rng::LaneRng::kValuesPerStep;
  for (std::size_t i = 0; i < n; i += kStep) {
    rng.next_values(r);
    const std::size_t m = n - i < kStep ? n - i : kStep;
    for (std::size_t j = 0; j < m; ++j) {
      const auto level = static_cast<std::size_t>(src[i + j] - lo);
      dst[i + j] = sample(tables + level * 256, r[j]);
    }
  }
}

#if FAULTLINE_X86_SIMD

// Eight samples: levels (8 x int32, already minus lo) and random bits -> 8 x int32 outcomes.
FAULTLINE_TARGET("avx2")
inline __m256i sample8(const std::uint32_t* tables, __m256i level, __m256i bits) {
  const __m256i bucket = _mm256_srli_epi32(bits, 24);
  const __m256i u = _mm256_and_si256(bits, _mm256_set1_epi32((1 << kDarkAliasThresholdBits) - 1));
  const __m256i idx = _mm256_or_si256(_mm256_slli_epi32(level, 8), bucket);
  const __m256i e = _mm256_i32gather_epi32(reinterpret_cast<const int*>(tables), idx, 4);
  const __m256i keep =
      _mm256_cmpgt_epi32(_mm256_srli_epi32(e, 8), u);  // both < 2^24: signed compare is exact
  return _mm256_blendv_epi8(_mm256_and_si256(e, _mm256_set1_epi32(0xFF)), bucket, keep);
}

// Processes whole blocks of 32 elements (two generator steps); returns how many elements it wrote.
FAULTLINE_TARGET("avx2")
std::size_t sample_avx2(const std::uint32_t* tables, int lo, const std::uint8_t* src,
                        std::uint8_t* dst, std::size_t n, rng::LaneRng& rng) {
  rng::avx2::Xoshiro4 a = rng::avx2::load_half(rng, 0), b = rng::avx2::load_half(rng, 1);
  const __m256i vlo = _mm256_set1_epi32(lo);
  const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  std::size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    const __m128i in = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + i));
    const __m128i in2 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + i + 16));
    const __m256i l0 = _mm256_sub_epi32(_mm256_cvtepu8_epi32(in), vlo);
    const __m256i l1 = _mm256_sub_epi32(_mm256_cvtepu8_epi32(_mm_srli_si128(in, 8)), vlo);
    const __m256i l2 = _mm256_sub_epi32(_mm256_cvtepu8_epi32(in2), vlo);
    const __m256i l3 = _mm256_sub_epi32(_mm256_cvtepu8_epi32(_mm_srli_si128(in2, 8)), vlo);
    const __m256i r0 = rng::avx2::step(a), r1 = rng::avx2::step(b);
    const __m256i r2 = rng::avx2::step(a), r3 = rng::avx2::step(b);
    const __m256i o0 = sample8(tables, l0, r0);
    const __m256i o1 = sample8(tables, l1, r1);
    const __m256i o2 = sample8(tables, l2, r2);
    const __m256i o3 = sample8(tables, l3, r3);
    // 32-bit -> bytes; the two packs interleave 128-bit lanes, the permute restores element order.
    const __m256i p = _mm256_packus_epi16(_mm256_packus_epi32(o0, o1), _mm256_packus_epi32(o2, o3));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + i), _mm256_permutevar8x32_epi32(p, order));
  }
  rng::avx2::store_half(a, rng, 0);
  rng::avx2::store_half(b, rng, 1);
  return i;
}
#endif

// Plain min/max reduction the compiler vectorises (eight times faster than cv::minMaxLoc on a
// frame).
FAULTLINE_CLONES("avx2")
void min_max(const std::uint8_t* __restrict src, std::size_t n, std::uint8_t* lo_out,
             std::uint8_t* hi_out) {
  std::uint8_t lo = 255, hi = 0;
  for (std::size_t i = 0; i < n; ++i) {
    lo = src[i] < lo ? src[i] : lo;
    hi = src[i] > hi ? src[i] : hi;
  }
  *lo_out = lo;
  *hi_out = hi;
}

}  // namespace

std::pair<int, int> dark_min_max(const std::uint8_t* src, std::size_t n) {
  if (n == 0) return {0, 0};
  std::uint8_t lo = 0, hi = 0;
  min_max(src, n, &lo, &hi);
  return {lo, hi};
}

void dark_sample(const std::uint32_t* tables, int lo, const std::uint8_t* src, std::uint8_t* dst,
                 std::size_t n, rng::LaneRng& rng, bool allow_simd) {
  std::size_t done = 0;
#if FAULTLINE_X86_SIMD
  if (allow_simd && common::cpu_has_avx2()) done = sample_avx2(tables, lo, src, dst, n, rng);
#else
  (void)allow_simd;
#endif
  sample_scalar(tables, lo, src + done, dst + done, n - done, rng);
}

void build_alias_entries(const double* prob, std::uint32_t* entry) {
  std::array<double, 256> scaled{};
  double total = 0.0;
  for (int j = 0; j < 256; ++j) total += prob[j];
  std::array<int, 256> small{}, large{};
  int ns = 0, nl = 0;
  for (int j = 0; j < 256; ++j) {
    scaled[static_cast<std::size_t>(j)] = prob[j] / total * 256.0;
    if (scaled[static_cast<std::size_t>(j)] < 1.0) {
      small[static_cast<std::size_t>(ns++)] = j;
    } else {
      large[static_cast<std::size_t>(nl++)] = j;
    }
  }
  constexpr std::uint32_t kKeep = 1u << kDarkAliasThresholdBits;  // u < threshold keeps the bucket
  constexpr double kOne = kKeep;
  for (int j = 0; j < 256; ++j) entry[j] = (kKeep << 8) | static_cast<std::uint32_t>(j);
  while (ns > 0 && nl > 0) {
    const int s = small[static_cast<std::size_t>(--ns)];
    const int l = large[static_cast<std::size_t>(nl - 1)];
    const auto threshold =
        static_cast<std::uint32_t>(std::llround(scaled[static_cast<std::size_t>(s)] * kOne));
    entry[s] = (threshold << 8) | static_cast<std::uint32_t>(l);
    scaled[static_cast<std::size_t>(l)] -= 1.0 - scaled[static_cast<std::size_t>(s)];
    if (scaled[static_cast<std::size_t>(l)] < 1.0) {
      --nl;
      small[static_cast<std::size_t>(ns++)] = l;
    }
  }
  // Leftovers (rounding) keep their own bucket always, as initialised.
}

}  // namespace faultline::corruption
