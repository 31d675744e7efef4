// Dark in numpy mode: the reference's draws (all H*W*3 Poissons, then all normals) on NumPy's
// legacy stream. The read noise is evaluated four polar pairs at a time with an approximate log;
// every byte is either proven equal to the glibc-log result by a bracket, or recomputed with
// glibc's log.
#include "corruption/dark_exact.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "common/simd.hpp"
#include "corruption/dark.hpp"
#include "corruption/dark_sampler.hpp"

namespace faultline::corruption {

namespace detail {

namespace {

// ln m = 2 atanh(t) = 2t (1 + t^2/3 + t^4/5 + ...), t = (m - 1)/(m + 1), m in [sqrt(1/2), sqrt(2)):
// |t| <= 0.1716, t^2 <= 0.02944. Terms through t^14/15 are kept; the rest is < t^16/17 / (1 - t^2)
// ~ 3.3e-14 of the sum.
constexpr double kSeries[] = {1.0,     1.0 / 3,  1.0 / 5,  1.0 / 7,
                              1.0 / 9, 1.0 / 11, 1.0 / 13, 1.0 / 15};
constexpr std::uint64_t kSqrtHalfMantissa = 0x0006A09E667F3BCDull;  // mantissa bits of sqrt(1/2)
constexpr double kLn2 = 0.6931471805599453;
constexpr double kTwo52 = 4503599627370496.0;

}  // namespace

// x = m 2^e: e' = the biased exponent of x, minus one when x's mantissa is below sqrt(2)'s, so e =
// e' - 1022 and m = x 2^-e lands in [sqrt(1/2), sqrt(2)). Then ln x = e ln 2 + ln m; for e != 0,
// |ln x| >= 0.34 > |ln m|, so the series' relative error carries over to ln x, and n ln 2 adds one
// rounding.
double approx_log(double x) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  const std::uint64_t biased = (bits - kSqrtHalfMantissa) >> 52;
  const std::uint64_t m_bits = bits - ((biased - 1022u) << 52);
  double m = 0.0;
  std::memcpy(&m, &m_bits, sizeof m);
  const double e = static_cast<double>(static_cast<std::int64_t>(biased) - 1022);
  const double t = (m - 1.0) / (m + 1.0);
  const double t2 = t * t;
  double s = kSeries[7];
  for (int j = 6; j >= 0; --j) s = s * t2 + kSeries[j];
  return e * kLn2 + (t + t) * s;
}

namespace {

constexpr std::size_t kChunkPairs =
    512;  // polar pairs drawn and evaluated per step of the noise stage

// The reference's byte for read noise z on top of y: trunc(clip(y + normal(0, sigma), 0, 1) * 255).
inline std::uint8_t noise_byte(double y, double sigma, double z) {
  const double v = y + (0.0 + sigma * z);
  return static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0);
}

#if FAULTLINE_X86_SIMD

FAULTLINE_TARGET("avx2") inline __m256d approx_log4(__m256d x) {
  const __m256i bits = _mm256_castpd_si256(x);
  const __m256i biased = _mm256_srli_epi64(
      _mm256_sub_epi64(bits, _mm256_set1_epi64x(static_cast<long long>(kSqrtHalfMantissa))), 52);
  const __m256i m_bits = _mm256_sub_epi64(
      bits, _mm256_slli_epi64(_mm256_sub_epi64(biased, _mm256_set1_epi64x(1022)), 52));
  const __m256d m = _mm256_castsi256_pd(m_bits);
  // biased < 2^11: OR-ing it into 2^52's mantissa makes the double 2^52 + biased exactly.
  const __m256d e = _mm256_sub_pd(
      _mm256_castsi256_pd(_mm256_or_si256(biased, _mm256_castpd_si256(_mm256_set1_pd(kTwo52)))),
      _mm256_set1_pd(kTwo52 + 1022.0));
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d t = _mm256_div_pd(_mm256_sub_pd(m, one), _mm256_add_pd(m, one));
  const __m256d t2 = _mm256_mul_pd(t, t);
  __m256d s = _mm256_set1_pd(kSeries[7]);
  for (int j = 6; j >= 0; --j) s = _mm256_add_pd(_mm256_mul_pd(s, t2), _mm256_set1_pd(kSeries[j]));
  return _mm256_add_pd(_mm256_mul_pd(e, _mm256_set1_pd(kLn2)),
                       _mm256_mul_pd(_mm256_add_pd(t, t), s));
}

// Bytes of 4 elements for factors f (one per element), values x, levels y: cvtt gives trunc for
// 0..255.
FAULTLINE_TARGET("avx2")
inline __m128i noise_bytes4(__m256d f, __m256d x, __m256d y, __m256d sigma) {
  const __m256d v = _mm256_add_pd(y, _mm256_mul_pd(sigma, _mm256_mul_pd(f, x)));
  const __m256d c = _mm256_min_pd(_mm256_max_pd(v, _mm256_setzero_pd()), _mm256_set1_pd(1.0));
  return _mm256_cvttpd_epi32(_mm256_mul_pd(c, _mm256_set1_pd(255.0)));
}

// Elements 0..8*groups of a chunk (pairs 0..4*groups). The bytes of both bracket ends go out;
// offsets where they differ are appended to `flagged`. Returns the new flag count.
FAULTLINE_TARGET("avx2")
std::size_t noise_groups_avx2(const double* x, const double* r2, std::size_t groups,
                              const std::uint8_t* counts, const double* y_of_k, double sigma,
                              double bracket, std::uint8_t* dst, std::uint16_t* flagged,
                              std::size_t nflag) {
  const __m256d sig = _mm256_set1_pd(sigma);
  const __m256d lo_scale = _mm256_set1_pd(1.0 - bracket), hi_scale = _mm256_set1_pd(1.0 + bracket);
  const __m256d minus_two = _mm256_set1_pd(-2.0);
  // The factors first, in a loop of their own: its iterations are independent, so the long divide
  // and square root latencies of several groups overlap.
  alignas(32) double factors[kChunkPairs];
  for (std::size_t g = 0; g < groups; ++g) {
    const __m256d r = _mm256_loadu_pd(r2 + 4 * g);
    _mm256_store_pd(factors + 4 * g,
                    _mm256_sqrt_pd(_mm256_div_pd(_mm256_mul_pd(minus_two, approx_log4(r)), r)));
  }
  for (std::size_t g = 0; g < groups; ++g) {
    const __m256d f = _mm256_load_pd(factors + 4 * g);
    const __m256d flo = _mm256_mul_pd(f, lo_scale), fhi = _mm256_mul_pd(f, hi_scale);
    // Element 2q uses pair q's factor on x2, element 2q + 1 on x1: each factor twice, in order.
    const __m256d flo_a = _mm256_permute4x64_pd(flo, 0x50),
                  flo_b = _mm256_permute4x64_pd(flo, 0xFA);
    const __m256d fhi_a = _mm256_permute4x64_pd(fhi, 0x50),
                  fhi_b = _mm256_permute4x64_pd(fhi, 0xFA);
    const __m256d xa = _mm256_loadu_pd(x + 8 * g), xb = _mm256_loadu_pd(x + 8 * g + 4);
    std::int64_t packed = 0;
    std::memcpy(&packed, counts + 8 * g, sizeof packed);
    const __m128i k8 = _mm_cvtsi64_si128(packed);
    // The masked form with a zero source: the plain one starts from an undefined register (a GCC
    // warning).
    const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    const __m256d ya =
        _mm256_mask_i32gather_pd(_mm256_setzero_pd(), y_of_k, _mm_cvtepu8_epi32(k8), all, 8);
    const __m256d yb = _mm256_mask_i32gather_pd(_mm256_setzero_pd(), y_of_k,
                                                _mm_cvtepu8_epi32(_mm_srli_si128(k8, 4)), all, 8);
    const __m128i lo_a = noise_bytes4(flo_a, xa, ya, sig), hi_a = noise_bytes4(fhi_a, xa, ya, sig);
    const __m128i lo_b = noise_bytes4(flo_b, xb, yb, sig), hi_b = noise_bytes4(fhi_b, xb, yb, sig);
    const __m128i bytes = _mm_packus_epi16(_mm_packs_epi32(lo_a, lo_b), _mm_setzero_si128());
    _mm_storel_epi64(reinterpret_cast<__m128i*>(dst + 8 * g), bytes);
    const __m128i same = _mm_packs_epi32(_mm_cmpeq_epi32(lo_a, hi_a), _mm_cmpeq_epi32(lo_b, hi_b));
    auto differ = static_cast<unsigned>(~_mm_movemask_epi8(same)) & 0xFFFFu;
    while (differ != 0) {
      const int bit = __builtin_ctz(differ);
      flagged[nflag++] = static_cast<std::uint16_t>(8 * g + static_cast<std::size_t>(bit / 2));
      differ &= ~(3u << bit);
    }
  }
  return nflag;
}

FAULTLINE_TARGET("avx2") void store_approx_log4(const double* x, double* out) {
  _mm256_storeu_pd(out, approx_log4(_mm256_loadu_pd(x)));
}

#endif

}  // namespace

void approx_logs(const double* x, double* out, std::size_t n) {
  std::size_t i = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) {
    for (; i + 4 <= n; i += 4) store_approx_log4(x + i, out + i);
  }
#endif
  for (; i < n; ++i) out[i] = approx_log(x[i]);
}

cv::Mat dark_exact_bracketed(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng,
                             double bracket) {
  const DarkParams p = dark_params(severity);
  const cv::Mat in = bgr.isContinuous() ? bgr : bgr.clone();
  const std::size_t n = in.total() * 3;
  const auto [lo, hi] = dark_min_max(in.data, n);
  double lam[256];
  dark_lambdas(lo, hi, severity, lam);
  rng::PoissonParams prepared[256];
  for (int v = 0; v < 256; ++v) prepared[v] = rng::prepare_poisson(lam[v]);
  auto y_for = [&](std::int64_t k) {
    return (std::min(std::max(static_cast<double>(k) / p.poisson_scale, 0.0), 1.0) * 255.0) / 255.0;
  };
  double y_of_k[256];
  for (int k = 0; k < 256; ++k) y_of_k[k] = y_for(k);

  // All Poisson draws come before all normal draws, so the counts are kept (a byte each; 255 and up
  // aside).
  thread_local std::vector<std::uint8_t> counts;
  counts.resize(n);
  std::vector<rng::LargeCount> large;
  rng.poissons(prepared, in.data, n, counts.data(), large);
  auto y_at = [&](std::size_t e) {
    if (counts[e] < 255) return y_of_k[counts[e]];
    const auto it =
        std::lower_bound(large.begin(), large.end(), e,
                         [](const rng::LargeCount& c, std::size_t i) { return c.index < i; });
    return y_for(it->count);
  };

  cv::Mat out(in.size(), in.type());
  std::uint8_t* dst = out.data;
  const double sigma = p.sigma;
  std::size_t i = 0;
  double cached = 0.0;
  if (n > 0 && rng.take_cached_normal(cached)) {
    dst[0] = noise_byte(y_at(0), sigma, cached);
    i = 1;
  }
  alignas(32) double x[2 * kChunkPairs];
  alignas(32) double r2[kChunkPairs];
  std::uint16_t flagged[2 * kChunkPairs];
  auto exact = [&](std::size_t chunk_start, std::size_t off) {
    dst[chunk_start + off] =
        noise_byte(y_at(chunk_start + off), sigma, rng::polar_factor(r2[off / 2]) * x[off]);
  };
  std::size_t next_large = i;  // a large count at element 0 was handled with the cached normal
  while (n - i >= 2) {
    const std::size_t pairs = std::min(kChunkPairs, (n - i) / 2);
    rng.polar_pairs(x, r2, pairs);
    std::size_t done_pairs = 0, nflag = 0;
#if FAULTLINE_X86_SIMD
    if (common::cpu_has_avx2()) {
      const std::size_t groups = pairs / 4;
      nflag = noise_groups_avx2(x, r2, groups, counts.data() + i, y_of_k, sigma, bracket, dst + i,
                                flagged, 0);
      done_pairs = 4 * groups;
    }
#endif
    for (std::size_t f = 0; f < nflag; ++f) exact(i, flagged[f]);
    for (std::size_t off = 2 * done_pairs; off < 2 * pairs; ++off) exact(i, off);
    // Counts of 255 and more were evaluated with y_of_k[255] above; their real y differs.
    for (; next_large < large.size() && large[next_large].index < i + 2 * pairs; ++next_large) {
      exact(i, large[next_large].index - i);
    }
    i += 2 * pairs;
  }
  if (i < n) {  // one value left: it opens a pair whose other half stays cached
    rng.polar_pairs(x, r2, 1);
    exact(i, 0);
    rng.cache_pair_half(x[1], r2[0]);
  }
  return out;
}

}  // namespace detail

cv::Mat dark_exact(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  return detail::dark_exact_bracketed(bgr, severity, rng, detail::kDefaultFactorBracket);
}

}  // namespace faultline::corruption
