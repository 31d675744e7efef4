// fast mode's water: the liquid field streamed row by row into liquid8, and the strength from its
// edges (Canny, exact capped distance, the 8-bit filters fused into one pass).
#include "corruption/spatter_water.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/simd.hpp"
#include "corruption/edge_canny.hpp"
#include "rng/lane_rng.hpp"
#include "rng/lane_rng_avx2.hpp"

namespace faultline::corruption {

namespace {

// The water's field is drawn and smoothed a row at a time, straight into liquid8 (the float field
// itself is never stored). Its draws are triangular, lo16 + hi16 of one 32-bit draw (no ziggurat,
// no table gather, no rejection), scaled to the normal's mean and variance: after the Gaussian
// (sigma 2-4) each field value is a weighted sum of ~2 pi sigma^2 = 25-100 effective draws, whose
// excess kurtosis is the draw's (-0.6) times sum w^4 / (sum w^2)^2 = 1 / (2 pi sigma^2): -0.024,
// -0.011 and -0.006 at sigma 2, 3, 4 (normal draws: 0). By the Edgeworth series that moves the
// liquid fraction (threshold 0.7-1.9 sd above the mean) by +0.0005 or less; measured over 48
// frames of 1600 x 900: +0.0002, +0.0006, +0.0009 (+-0.0003-0.0005) on 0.03, 0.15, 0.24 at
// severities 1, 2, 3.

// n draws lo16 + hi16 - 65535 (exact in float), value i % 16 of lane step i / 16; a row of n takes
// ceil(n / 16) steps (a partial step's leftover values are dropped), on every CPU.
#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET_INLINE("avx2") inline __m256 triangular8(__m256i v) {
  const __m256i lo = _mm256_and_si256(v, _mm256_set1_epi32(0xFFFF));
  const __m256i sum = _mm256_add_epi32(lo, _mm256_srli_epi32(v, 16));
  return _mm256_cvtepi32_ps(_mm256_sub_epi32(sum, _mm256_set1_epi32(65535)));
}

FAULTLINE_TARGET("avx2")
std::size_t triangular_avx2(float* dst, std::size_t n, rng::LaneRng& lanes) {
  rng::avx2::Xoshiro4 a = rng::avx2::load_half(lanes, 0), b = rng::avx2::load_half(lanes, 1);
  std::size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    _mm256_storeu_ps(dst + i, triangular8(rng::avx2::step(a)));
    _mm256_storeu_ps(dst + i + 8, triangular8(rng::avx2::step(b)));
  }
  rng::avx2::store_half(a, lanes, 0);
  rng::avx2::store_half(b, lanes, 1);
  return i;
}
#endif

void triangular_row(float* dst, std::size_t n, rng::LaneRng& lanes, bool simd) {
  std::size_t i = 0;
#if FAULTLINE_X86_SIMD
  if (simd) i = triangular_avx2(dst, n, lanes);
#else
  (void)simd;
#endif
  std::uint32_t v[rng::LaneRng::kValuesPerStep];
  for (; i < n; i += rng::LaneRng::kValuesPerStep) {
    lanes.next_values(v);
    for (std::size_t j = 0; j < rng::LaneRng::kValuesPerStep && i + j < n; ++j) {
      const auto t = static_cast<std::int32_t>((v[j] & 0xFFFFu) + (v[j] >> 16)) - 65535;
      dst[i + j] = static_cast<float>(t);
    }
  }
}

// The Gaussian's passes: out = w0 c + sum_{k=1..r} w_k (lo_k + hi_k), summed in this order (no
// FMA), so the AVX2 bodies and the portable ones give the same floats. A row pass reads in[x +- k]
// (in padded by r each side); a column pass reads centre[+-k][x] (row pointers).
float blur_tap_sum(const float* in, const float* w, int r, std::size_t x) {
  float acc = w[0] * in[x];
  for (int k = 1; k <= r; ++k)
    acc += w[k] * (in[static_cast<std::ptrdiff_t>(x) - k] + in[x + static_cast<std::size_t>(k)]);
  return acc;
}

float column_tap_sum(const float* const* centre, const float* w, int r, std::size_t x) {
  float acc = w[0] * centre[0][x];
  for (int k = 1; k <= r; ++k) acc += w[k] * (centre[-k][x] + centre[k][x]);
  return acc;
}

// liquid8 = uint8(field * 255) (numpy's wrap) where field = loc + sum >= threshold, else 0.
std::uint8_t liquid_value(float sum, float loc, float threshold) {
  const float f = loc + sum;
  const float v = f >= threshold ? f * 255.f : 0.f;
  return static_cast<std::uint8_t>(static_cast<std::int32_t>(v) & 0xFF);
}

#if FAULTLINE_X86_SIMD
// Each output's taps are summed in a chain of dependent adds: blocks of 8 outputs side by side
// keep that many chains in flight.
template <int kBlocks>
FAULTLINE_TARGET("avx2")
std::size_t blur_row_avx2(float* out, const float* in, const float* w, int r, std::size_t x,
                          std::size_t n) {
  for (; x + 8 * kBlocks <= n; x += 8 * kBlocks) {
    __m256 acc[kBlocks];
    for (int b = 0; b < kBlocks; ++b) {
      acc[b] = _mm256_mul_ps(_mm256_set1_ps(w[0]), _mm256_loadu_ps(in + x + 8 * b));
    }
    for (int k = 1; k <= r; ++k) {
      const __m256 wk = _mm256_set1_ps(w[k]);
      for (int b = 0; b < kBlocks; ++b) {
        const float* at = in + x + 8 * b;
        const __m256 pair = _mm256_add_ps(_mm256_loadu_ps(at - k), _mm256_loadu_ps(at + k));
        acc[b] = _mm256_add_ps(acc[b], _mm256_mul_ps(wk, pair));
      }
    }
    for (int b = 0; b < kBlocks; ++b) _mm256_storeu_ps(out + x + 8 * b, acc[b]);
  }
  return x;
}

// liquid8 of the outputs x .. x + 8 kBlocks - 1 as int32 lanes (the column pass, then the
// threshold and the wrap).
template <int kBlocks>
FAULTLINE_TARGET_INLINE("avx2")
inline void liquid_blocks(__m256i (&value)[kBlocks], const float* const* centre, const float* w,
                          int r, __m256 loc, __m256 threshold, std::size_t x) {
  __m256 acc[kBlocks];
  for (int b = 0; b < kBlocks; ++b) {
    acc[b] = _mm256_mul_ps(_mm256_set1_ps(w[0]), _mm256_loadu_ps(centre[0] + x + 8 * b));
  }
  for (int k = 1; k <= r; ++k) {
    const __m256 wk = _mm256_set1_ps(w[k]);
    const float* lo = centre[-k] + x;
    const float* hi = centre[k] + x;
    for (int b = 0; b < kBlocks; ++b) {
      const __m256 pair = _mm256_add_ps(_mm256_loadu_ps(lo + 8 * b), _mm256_loadu_ps(hi + 8 * b));
      acc[b] = _mm256_add_ps(acc[b], _mm256_mul_ps(wk, pair));
    }
  }
  for (int b = 0; b < kBlocks; ++b) {
    const __m256 f = _mm256_add_ps(loc, acc[b]);
    const __m256 v = _mm256_and_ps(_mm256_cmp_ps(f, threshold, _CMP_GE_OQ),
                                   _mm256_mul_ps(f, _mm256_set1_ps(255.f)));
    value[b] = _mm256_and_si256(_mm256_cvttps_epi32(v), _mm256_set1_epi32(0xFF));
  }
}

// 16 int32 lanes (each 0..255) to 16 bytes in order.
FAULTLINE_TARGET_INLINE("avx2") inline __m128i pack16(__m256i a, __m256i b) {
  const __m256i words = _mm256_permute4x64_epi64(_mm256_packus_epi32(a, b), 0xD8);
  return _mm_packus_epi16(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
}

FAULTLINE_TARGET("avx2")
std::size_t column_liquid_avx2(std::uint8_t* out, const float* const* centre, const float* w, int r,
                               float loc, float threshold, std::size_t n) {
  const __m256 locv = _mm256_set1_ps(loc), thr = _mm256_set1_ps(threshold);
  std::size_t x = 0;
  for (; x + 32 <= n; x += 32) {
    __m256i v[4];
    liquid_blocks<4>(v, centre, w, r, locv, thr, x);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), pack16(v[0], v[1]));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x + 16), pack16(v[2], v[3]));
  }
  for (; x + 16 <= n; x += 16) {
    __m256i v[2];
    liquid_blocks<2>(v, centre, w, r, locv, thr, x);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), pack16(v[0], v[1]));
  }
  return x;
}
#endif

void blur_row(float* out, const float* in, const float* w, int r, std::size_t n, bool simd) {
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (simd) x = blur_row_avx2<1>(out, in, w, r, blur_row_avx2<4>(out, in, w, r, 0, n), n);
#else
  (void)simd;
#endif
  for (; x < n; ++x) out[x] = blur_tap_sum(in, w, r, x);
}

void column_liquid_row(std::uint8_t* out, const float* const* centre, const float* w, int r,
                       float loc, float threshold, std::size_t n, bool simd) {
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (simd) x = column_liquid_avx2(out, centre, w, r, loc, threshold, n);
#else
  (void)simd;
#endif
  for (; x < n; ++x) out[x] = liquid_value(column_tap_sum(centre, w, r, x), loc, threshold);
}

// Vertical distance to the nearest edge pixel in the column, capped at kCap + 1: from the row
// above, d = edge ? 0 : min(above + 1, kCap + 1) (kCap + 1 on the first row: above = nullptr),
// then from the row below, d = min(d, below + 1).
constexpr int kCap = 20;
FAULTLINE_CLONES("avx2")
void column_down(std::uint8_t* __restrict d, const std::uint8_t* above, const std::uint8_t* edge,
                 std::size_t n) {
  for (std::size_t x = 0; x < n; ++x) {
    const int from = above ? std::min(above[x] + 1, kCap + 1) : kCap + 1;
    d[x] = static_cast<std::uint8_t>(edge[x] ? 0 : from);
  }
}

FAULTLINE_CLONES("avx2")
void column_up(std::uint8_t* __restrict d, const std::uint8_t* below, std::size_t n) {
  for (std::size_t x = 0; x < n; ++x)
    d[x] = static_cast<std::uint8_t>(std::min<int>(d[x], below[x] + 1));
}

// One row of distances: d = min(sqrt(d2), kCap) with d2 = min over |k| <= kCap of
// k^2 + dv(x + k)^2, from dv^2 padded by kCap values of (kCap + 1)^2 each side (`q` at the first
// real one). The square roots are correctly rounded in both bodies (vsqrtps and std::sqrt).
float distance_value(const std::uint16_t* q, std::size_t x) {
  int d2 = q[x];
  for (int k = 1; k <= kCap && k * k < d2; ++k) {  // k^2 >= d2: no farther column is nearer
    d2 = std::min(
        d2, std::min(q[static_cast<std::ptrdiff_t>(x) - k], q[x + static_cast<std::size_t>(k)]) +
                k * k);
  }
  return std::min(std::sqrt(static_cast<float>(d2)), static_cast<float>(kCap));
}

#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET_INLINE("avx2") inline __m256i load16(const std::uint16_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

// The largest of 16 unsigned 16-bit lanes.
FAULTLINE_TARGET_INLINE("avx2") inline int largest16(__m256i v) {
  __m128i m = _mm_max_epu16(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
  m = _mm_max_epu16(m, _mm_srli_si128(m, 8));
  m = _mm_max_epu16(m, _mm_srli_si128(m, 4));
  m = _mm_max_epu16(m, _mm_srli_si128(m, 2));
  return _mm_extract_epi16(m, 0);
}

FAULTLINE_TARGET("avx2")
std::size_t distance_avx2(float* d, const std::uint16_t* q, std::size_t n) {
  static_assert(kCap >= 4, "the window loads below cover x - kCap .. x + 15 + kCap");
  const __m256 cap = _mm256_set1_ps(static_cast<float>(kCap));
  std::size_t x = 0;
  const __m256i far = _mm256_set1_epi16((kCap + 1) * (kCap + 1));
  for (; x + 16 <= n; x += 16) {
    // No edge within kCap columns of the 16 (their window x - kCap .. x + 15 + kCap all at the
    // cap): every distance is kCap, as the loop below would find (most blocks away from liquid).
    const __m256i window =
        _mm256_min_epu16(_mm256_min_epu16(load16(q + x - kCap), load16(q + x - 4)),
                         _mm256_min_epu16(load16(q + x + 12), load16(q + x + kCap)));
    if (_mm256_movemask_epi8(_mm256_cmpeq_epi16(window, far)) == -1) {
      _mm256_storeu_ps(d + x, cap);
      _mm256_storeu_ps(d + x + 8, cap);
      continue;
    }
    __m256i d2 = load16(q + x);
    for (int k = 1; k <= kCap; ++k) {
      // Once k^2 reaches every lane's d2, no farther column can lower any (q >= 0): stop. Checked
      // every fourth step (the lanes' maximum costs a few shuffles).
      if ((k & 3) == 0 && k * k >= largest16(d2)) break;
      const __m256i pair = _mm256_min_epu16(load16(q + x - k), load16(q + x + k));
      d2 = _mm256_min_epu16(
          d2, _mm256_add_epi16(pair, _mm256_set1_epi16(static_cast<std::int16_t>(k * k))));
    }
    const __m256 lo = _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm256_castsi256_si128(d2)));
    const __m256 hi = _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm256_extracti128_si256(d2, 1)));
    _mm256_storeu_ps(d + x, _mm256_min_ps(_mm256_sqrt_ps(lo), cap));
    _mm256_storeu_ps(d + x + 8, _mm256_min_ps(_mm256_sqrt_ps(hi), cap));
  }
  return x;
}
#endif

void distance_row(float* d, const std::uint16_t* q, std::size_t n, bool simd) {
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (simd) x = distance_avx2(d, q, n);
#else
  (void)simd;
#endif
  for (; x < n; ++x) d[x] = distance_value(q, x);
}

// hist[v] += the count of v in the row, for v = 0..kCap (the only values of the strength's
// distances). AVX2: per value, byte counters (cmpeq subtracted) over at most 255 vectors, summed
// by vpsadbw.
#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET("avx2")
std::size_t count_avx2(int* hist, const std::uint8_t* d, std::size_t n) {
  const std::size_t vectors = n / 32;
  for (int v = 0; v <= kCap; ++v) {
    const __m256i value = _mm256_set1_epi8(static_cast<char>(v));
    std::int64_t total = 0;
    for (std::size_t i = 0; i < vectors;) {
      const std::size_t end = std::min(vectors, i + 255);
      __m256i counts = _mm256_setzero_si256();
      for (; i < end; ++i) {
        const __m256i bytes = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(d + 32 * i));
        counts = _mm256_sub_epi8(counts, _mm256_cmpeq_epi8(bytes, value));
      }
      const __m256i sums = _mm256_sad_epu8(counts, _mm256_setzero_si256());
      alignas(32) std::int64_t lanes[4];
      _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), sums);
      total += lanes[0] + lanes[1] + lanes[2] + lanes[3];
    }
    hist[v] += static_cast<int>(total);
  }
  return 32 * vectors;
}
#endif

void count_row(int* hist, const std::uint8_t* d, std::size_t n, bool simd) {
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (simd) x = count_avx2(hist, d, n);
#else
  (void)simd;
#endif
  for (; x < n; ++x) ++hist[d[x]];
}

// out = floor(3 x 3 mean) of the rows a, b, c, columns reflected (reflect-101) at both ends.
FAULTLINE_CLONES("avx2")
void mean3_row(std::uint8_t* out, float* sum, const float* a, const float* b, const float* c,
               std::size_t n) {
  for (std::size_t x = 0; x < n; ++x) sum[x] = a[x] + b[x] + c[x];
  const auto at = [&](std::ptrdiff_t x) {
    const auto last = static_cast<std::ptrdiff_t>(n) - 1;
    return sum[static_cast<std::size_t>(
        x < 0 ? std::min<std::ptrdiff_t>(1, last)
              : (x > last ? std::max<std::ptrdiff_t>(last - 1, 0) : x))];
  };
  out[0] = static_cast<std::uint8_t>(static_cast<std::int32_t>((at(-1) + at(0) + at(1)) / 9.f));
  for (std::size_t x = 1; x + 1 < n; ++x) {
    out[x] = static_cast<std::uint8_t>(
        static_cast<std::int32_t>((sum[x - 1] + sum[x] + sum[x + 1]) * (1.f / 9.f)));
  }
  if (n > 1) {
    const auto l = static_cast<std::ptrdiff_t>(n) - 1;
    out[n - 1] =
        static_cast<std::uint8_t>(static_cast<std::int32_t>((at(l - 1) + at(l) + at(l + 1)) / 9.f));
  }
}

// out = floor of the 3 x 3 mean (cv::blur's default reflect-101 border) of the distance to the
// nearest Canny edge pixel, capped at 20 (CV_8U), three rows of distances at a time; dv: scratch.
void edge_distance_u8(const cv::Mat& edges, cv::Mat& dv, cv::Mat& out) {
  const int rows = edges.rows;
  const auto n = static_cast<std::size_t>(edges.cols);
  dv.create(edges.size(), CV_8U);
  for (int y = 0; y < rows; ++y) {
    column_down(dv.ptr<std::uint8_t>(y), y ? dv.ptr<std::uint8_t>(y - 1) : nullptr,
                edges.ptr<std::uint8_t>(y), n);
  }
  for (int y = rows - 2; y >= 0; --y) {
    column_up(dv.ptr<std::uint8_t>(y), dv.ptr<std::uint8_t>(y + 1), n);
  }
  std::vector<std::uint16_t> q(n + 2 * kCap, (kCap + 1) * (kCap + 1));
  const bool simd = common::cpu_has_avx2();
  std::vector<float> ring(3 * n), sum(n);
  auto distances = [&](int y) {  // row y's distances into ring slot y % 3
    const std::uint8_t* v = dv.ptr<std::uint8_t>(y);
    for (std::size_t x = 0; x < n; ++x) q[x + kCap] = static_cast<std::uint16_t>(v[x] * v[x]);
    distance_row(ring.data() + static_cast<std::size_t>(y % 3) * n, q.data() + kCap, n, simd);
  };
  auto reflect = [rows](int y) {
    return y < 0 ? std::min(1, rows - 1) : (y >= rows ? std::max(rows - 2, 0) : y);
  };
  out.create(edges.size(), CV_8U);
  int done = -1;
  for (int y = 0; y < rows; ++y) {
    for (; done < std::min(y + 1, rows - 1); ++done) distances(done + 1);
    const float* a = ring.data() + static_cast<std::size_t>(reflect(y - 1) % 3) * n;
    const float* b = ring.data() + static_cast<std::size_t>(y % 3) * n;
    const float* c = ring.data() + static_cast<std::size_t>(reflect(y + 1) % 3) * n;
    mean3_row(out.ptr<std::uint8_t>(y), sum.data(), a, b, c, n);
  }
}

// cv::equalizeHist's table for a histogram of `total` values: 0 from the lowest value present,
// then round(255 cumulative / (total - its count)) in float; a single value maps to itself.
std::array<std::uint8_t, 256> equalize_table(const std::array<int, 256>& hist, int total) {
  std::array<std::uint8_t, 256> table{};
  std::size_t i = 0;
  while (i < 255 && hist[i] == 0) ++i;
  if (hist[i] == total) {
    table.fill(static_cast<std::uint8_t>(i));
    return table;
  }
  const float scale = 255.f / static_cast<float>(total - hist[i]);
  int sum = 0;
  for (table[i++] = 0; i < 256; ++i) {
    sum += hist[i];
    const long v = std::lrint(static_cast<float>(sum) * scale);
    table[i] = static_cast<std::uint8_t>(std::clamp(v, 0L, 255L));
  }
  return table;
}

// Reflect-101 (OpenCV's default border) of row or column index i in [0, size).
int reflect101(int i, int size) {
  if (size == 1) return 0;
  return i < 0 ? -i : (i >= size ? 2 * size - 2 - i : i);
}

// One row of the emboss kernel (-2 -1 0 / -1 1 1 / 0 1 2, correlated) over the rows a, b, c
// (index 0 is column -1), clipped to 0..255 as filter2D's 8-bit output.
FAULTLINE_CLONES("avx2")
void emboss_row(std::int16_t* __restrict out, const std::int16_t* a, const std::int16_t* b,
                const std::int16_t* c, std::size_t n) {
  for (std::size_t x = 0; x < n; ++x) {
    const int v = -2 * a[x] - a[x + 1] - b[x] + b[x + 1] + b[x + 2] + c[x + 1] + 2 * c[x + 2];
    out[x] = static_cast<std::int16_t>(std::min(std::max(v, 0), 255));
  }
}

// One row of the 3 x 3 mean, rounded, over the rows a, b, c (index 0 is column -1), and the
// largest liquid * mean of the row.
FAULTLINE_CLONES("avx2")
int mean_row(std::uint8_t* __restrict out, std::int16_t* __restrict sum, const std::int16_t* a,
             const std::int16_t* b, const std::int16_t* c, const std::uint8_t* liquid,
             std::size_t n) {
  for (std::size_t x = 0; x < n + 2; ++x) sum[x] = static_cast<std::int16_t>(a[x] + b[x] + c[x]);
  int best = 0;
  for (std::size_t x = 0; x < n; ++x) {
    const int mean = (sum[x] + sum[x + 1] + sum[x + 2] + 4) / 9;
    out[x] = static_cast<std::uint8_t>(mean);
    best = std::max(best, liquid[x] * mean);
  }
  return best;
}

// out = table[d] widened to int16, for d <= kCap (< 32): AVX2 looks the 32 entries up as two
// 16-byte shuffles.
#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET("avx2")
std::size_t lookup_avx2(std::int16_t* out, const std::uint8_t* d,
                        const std::array<std::uint8_t, 256>& table, std::size_t n) {
  static_assert(kCap < 32, "two 16-entry shuffles");
  const __m256i low =
      _mm256_broadcastsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(table.data())));
  const __m256i high = _mm256_broadcastsi128_si256(
      _mm_loadu_si128(reinterpret_cast<const __m128i*>(table.data() + 16)));
  std::size_t x = 0;
  for (; x + 32 <= n; x += 32) {
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(d + x));
    const __m256i mapped =
        _mm256_blendv_epi8(_mm256_shuffle_epi8(low, v), _mm256_shuffle_epi8(high, v),
                           _mm256_cmpgt_epi8(v, _mm256_set1_epi8(15)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + x),
                        _mm256_cvtepu8_epi16(_mm256_castsi256_si128(mapped)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + x + 16),
                        _mm256_cvtepu8_epi16(_mm256_extracti128_si256(mapped, 1)));
  }
  return x;
}
#endif

void lookup_row(std::int16_t* out, const std::uint8_t* d,
                const std::array<std::uint8_t, 256>& table, std::size_t n, bool simd) {
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (simd) x = lookup_avx2(out, d, table, n);
#else
  (void)simd;
#endif
  for (; x < n; ++x) out[x] = table[d[x]];
}

// In place: strength = blur3(emboss(table[strength])), both filters with the reflect-101 border,
// row by row through rings of three padded rows (row y is written after rows up to y + 2 are
// read); max_product = the largest liquid8 * strength.
void filter_strength(cv::Mat& strength, const cv::Mat& liquid8,
                     const std::array<std::uint8_t, 256>& table, int& max_product) {
  const int rows = strength.rows, cols = strength.cols;
  const auto n = static_cast<std::size_t>(cols);
  const std::size_t stride = n + 2;
  const bool simd = common::cpu_has_avx2();
  std::vector<std::int16_t> mapped(3 * stride), embossed(3 * stride), sum(stride);
  auto slot = [stride](std::vector<std::int16_t>& ring, int y) {
    return ring.data() + static_cast<std::size_t>(y % 3) * stride;
  };
  auto pad = [&](std::int16_t* row) {  // index 0 is column -1
    row[0] = row[1 + reflect101(-1, cols)];
    row[n + 1] = row[1 + reflect101(cols, cols)];
  };
  auto map_row = [&](int y) {
    std::int16_t* row = slot(mapped, y);
    const std::uint8_t* d = strength.ptr<std::uint8_t>(y);
    lookup_row(row + 1, d, table, n, simd);
    pad(row);
  };
  auto emboss = [&](int y) {
    std::int16_t* row = slot(embossed, y);
    emboss_row(row + 1, slot(mapped, reflect101(y - 1, rows)), slot(mapped, y),
               slot(mapped, reflect101(y + 1, rows)), n);
    pad(row);
  };
  max_product = 0;
  int mapped_to = 0, embossed_to = 0;  // rows done
  for (int y = 0; y < rows; ++y) {
    const int emboss_need = std::min(y + 1, rows - 1);
    for (; embossed_to <= emboss_need; ++embossed_to) {
      for (; mapped_to <= std::min(embossed_to + 1, rows - 1); ++mapped_to) map_row(mapped_to);
      emboss(embossed_to);
    }
    const int best =
        mean_row(strength.ptr<std::uint8_t>(y), sum.data(), slot(embossed, reflect101(y - 1, rows)),
                 slot(embossed, y), slot(embossed, reflect101(y + 1, rows)),
                 liquid8.ptr<std::uint8_t>(y), n);
    max_product = std::max(max_product, best);
  }
}

}  // namespace

// fast mode's liquid8 for the water: draws, then the Gaussian to 3 sigma (replicate border) as a
// row pass into a ring of 2r + 1 rows and a column pass per output row, with the draws' scale in
// the column taps.
void water_liquid8(cv::Size size, const SpatterParams& p, rng::FastRng& rng, WaterScratch& s) {
  const int r = static_cast<int>(std::ceil(3.0 * p.sigma));
  std::vector<double> taps(static_cast<std::size_t>(r) + 1);
  double total = 0;
  for (int k = 0; k <= r; ++k) {
    taps[static_cast<std::size_t>(k)] = std::exp(-0.5 * k * k / (p.sigma * p.sigma));
    total += (k ? 2 : 1) * taps[static_cast<std::size_t>(k)];
  }
  const double draw_sd = std::sqrt((4294967296.0 - 1.0) / 6.0);  // of lo16 + hi16 - 65535
  std::vector<float> row_w(taps.size()), col_w(taps.size());
  for (std::size_t k = 0; k < taps.size(); ++k) {
    row_w[k] = static_cast<float>(taps[k] / total);
    col_w[k] = static_cast<float>(taps[k] / total * p.scale / draw_sd);
  }
  const auto n = static_cast<std::size_t>(size.width);
  const auto ur = static_cast<std::size_t>(r);
  const int ring_rows = std::min(2 * r + 1, size.height);
  std::vector<float> padded(n + 2 * ur), ring(static_cast<std::size_t>(ring_rows) * n);
  std::vector<const float*> window(2 * ur + 1);
  auto ring_row = [&](int y) { return ring.data() + static_cast<std::size_t>(y % ring_rows) * n; };
  rng::LaneRng lanes(rng);
  const bool simd = common::cpu_has_avx2();
  cv::Mat& liquid8 = s.liquid8;
  liquid8.create(size, CV_8U);
  int drawn = 0;
  for (int y = 0; y < size.height; ++y) {
    for (; drawn <= std::min(y + r, size.height - 1); ++drawn) {
      triangular_row(padded.data() + ur, n, lanes, simd);
      std::fill(padded.begin(), padded.begin() + r, padded[ur]);
      std::fill(padded.end() - r, padded.end(), padded[ur + n - 1]);
      blur_row(ring_row(drawn), padded.data() + ur, row_w.data(), r, n, simd);
    }
    for (int k = -r; k <= r; ++k) {
      window[static_cast<std::size_t>(k + r)] = ring_row(std::clamp(y + k, 0, size.height - 1));
    }
    column_liquid_row(liquid8.ptr<std::uint8_t>(y), window.data() + r, col_w.data(), r,
                      static_cast<float>(p.loc), static_cast<float>(p.threshold), n, simd);
  }
}

int equalize_emboss_blur(cv::Mat& dist8, const cv::Mat& liquid8) {
  std::array<int, 256> hist{};
  const bool simd = common::cpu_has_avx2();
  for (int y = 0; y < dist8.rows; ++y) {
    count_row(hist.data(), dist8.ptr<std::uint8_t>(y), static_cast<std::size_t>(dist8.cols), simd);
  }
  int max_product = 0;
  filter_strength(dist8, liquid8, equalize_table(hist, static_cast<int>(dist8.total())),
                  max_product);
  return max_product;
}

int water_strength_fast(WaterScratch& s) {
  canny_l1(s.liquid8, 50, 150, s.edges, s.canny_map);
  edge_distance_u8(s.edges, s.distance, s.strength);
  return equalize_emboss_blur(s.strength, s.liquid8);
}

}  // namespace faultline::corruption
