// fast mode's mud: normals row by row, the field's blur and threshold, the mask's integer blur and
// the blend, each a pass over rows held in cache (AVX2 bodies with portable twins).
#include "corruption/spatter_mud.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "common/simd.hpp"
#include "corruption/fixed_point_blur.hpp"
#include "rng/lane_rng.hpp"
#include "rng/lane_rng_avx2.hpp"

namespace faultline::corruption {

namespace detail {
namespace {
constexpr std::int32_t kOne = 1 << 28;  // level of m = 1

// The portable loops, from element `from` on.
void field_columns(float* col, const float* const* rows, const float* w, int r, std::size_t from,
                   std::size_t n) {
  for (std::size_t x = from; x < n; ++x) {
    float acc = w[0] * rows[r][x];
    for (int k = 1; k <= r; ++k) acc = acc + w[k] * (rows[r - k][x] + rows[r + k][x]);
    col[x] = acc;
  }
}

void field_threshold(std::uint8_t* mask, const float* col, const float* w, int r, float threshold,
                     std::size_t from, std::size_t n) {
  for (std::size_t x = from; x < n; ++x) {
    const float* c = col + x;
    float acc = w[0] * c[0];
    for (int k = 1; k <= r; ++k) acc = acc + w[k] * (c[-k] + c[k]);
    mask[x] = acc > threshold ? 1 : 0;
  }
}

void level_columns(std::int16_t* col, const std::uint8_t* const* rows, const std::int16_t* w, int r,
                   std::size_t from, std::size_t n) {
  for (std::size_t x = from; x < n; ++x) {
    int acc = w[0] * rows[r][x];
    for (int k = 1; k <= r; ++k) acc += w[k] * (rows[r - k][x] + rows[r + k][x]);
    col[x] = static_cast<std::int16_t>(acc);  // <= 2^13
  }
}

void level_blend(std::uint8_t* out, const std::uint8_t* in, const std::int16_t* col,
                 const std::int16_t* w, int r, std::size_t from, std::size_t pixels) {
  for (std::size_t x = from; x < pixels; ++x) {
    const std::int16_t* c = col + x;
    std::int32_t level = w[0] * c[0];
    for (int k = 1; k <= r; ++k) level += w[k] * (c[-k] + c[k]);
    for (int ch = 0; ch < 3; ++ch) {
      const std::int32_t v = in[3 * x + ch];
      const std::int32_t u = (kOne - level + 4095) >> 12;
      out[3 * x + ch] = static_cast<std::uint8_t>(
          level < kMudLevelCut ? v : kMudColour[ch] + (((v - kMudColour[ch]) * u) >> 16));
    }
  }
}

// Box-Muller from one lane step's 16 values: v[i] (i < 8) gives the radius, v[8 + i] the angle
// of the pair (dst[i], dst[8 + i]). u = ((v >> 8) | 1) 2^-24 (the odd multiples of 2^-24 in
// (0, 1), exact in float32: r is at most 5.77), r = sqrt(-2 ln u)
// (ln u = e ln 2 + ln m, m in [sqrt(1/2), sqrt(2)) by the series 2 atanh t, t = (m - 1) / (m + 1),
// to t^9: |t| < 0.172, error < 1e-8); the angle: an octant's phi = (w & (2^29 - 1)) 2^-29 pi / 4
// (Taylor to phi^9 and phi^10), the pair (cos phi, sin phi) swapped by bit 29 and signed by bits
// 31 and 30 (the point on the circle is then uniform). Every operation is a float32 product, sum,
// quotient or square root, in the same order on both paths.
constexpr float kLn2 = 0.693147180559945f, kSqrt2 = 1.41421356237310f,
                kPiQuarter = 0.785398163397448f;

float ln_unit(float u) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &u, 4);
  int e = static_cast<int>(bits >> 23) - 127;
  const std::uint32_t mbits = (bits & 0x7FFFFFu) | 0x3F800000u;
  float m = 0;
  std::memcpy(&m, &mbits, 4);
  if (m > kSqrt2) {
    m = m * 0.5f;
    e = e + 1;
  }
  const float t = (m - 1.f) / (m + 1.f), t2 = t * t;
  const float series = 1.f + t2 * (1.f / 3 + t2 * (1.f / 5 + t2 * (1.f / 7 + t2 * (1.f / 9))));
  return static_cast<float>(e) * kLn2 + (t + t) * series;
}

void normals_step(float* dst, const std::uint32_t* v, float loc, float scale) {
  for (int i = 0; i < 8; ++i) {
    const float u = static_cast<float>(static_cast<std::int32_t>(v[i] >> 8 | 1u)) * 0x1p-24f;
    const float r = std::sqrt(std::max(-2.f * ln_unit(u), 0.f));
    const std::uint32_t w = v[8 + i];
    const float phi =
        static_cast<float>(static_cast<std::int32_t>(w & 0x1FFFFFFFu)) * 0x1p-29f * kPiQuarter;
    const float p2 = phi * phi;
    const float sin_phi =
        phi * (1.f + p2 * (-1.f / 6 + p2 * (1.f / 120 + p2 * (-1.f / 5040 + p2 * (1.f / 362880)))));
    const float cos_phi =
        1.f + p2 * (-0.5f + p2 * (1.f / 24 +
                                  p2 * (-1.f / 720 + p2 * (1.f / 40320 + p2 * (-1.f / 3628800)))));
    const bool swap = (w >> 29 & 1u) != 0;
    const float a = r * (swap ? sin_phi : cos_phi), b = r * (swap ? cos_phi : sin_phi);
    dst[i] = loc + scale * ((w >> 31) != 0 ? -a : a);
    dst[8 + i] = loc + scale * ((w >> 30 & 1u) != 0 ? -b : b);
  }
}

// The edge value repeated r times beyond each end of the row col[0..n).
template <typename T>
void fill_border(T* col, int r, std::size_t n) {
  for (int k = 1; k <= r; ++k) {
    col[-k] = col[0];
    col[n - 1 + static_cast<std::size_t>(k)] = col[n - 1];
  }
}

#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET_INLINE("avx2") inline __m256 f(float x) { return _mm256_set1_ps(x); }
FAULTLINE_TARGET_INLINE("avx2") inline __m256 add(__m256 a, __m256 b) {
  return _mm256_add_ps(a, b);
}
FAULTLINE_TARGET_INLINE("avx2") inline __m256 mul(__m256 a, __m256 b) {
  return _mm256_mul_ps(a, b);
}

// The same for eight pairs: the operations above, lane by lane.
FAULTLINE_TARGET("avx2")
std::size_t normals_avx2(float* dst, std::size_t n, float loc, float scale, rng::LaneRng& lanes) {
  rng::avx2::Xoshiro4 ga = rng::avx2::load_half(lanes, 0), gb = rng::avx2::load_half(lanes, 1);
  const __m256i mantissa = _mm256_set1_epi32(0x7FFFFF), one_bits = _mm256_set1_epi32(0x3F800000);
  std::size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    const __m256i v = rng::avx2::step(ga), w = rng::avx2::step(gb);
    const __m256i odd = _mm256_or_si256(_mm256_srli_epi32(v, 8), _mm256_set1_epi32(1));
    const __m256 u = mul(_mm256_cvtepi32_ps(odd), f(0x1p-24f));
    const __m256i bits = _mm256_castps_si256(u);
    __m256i e = _mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127));
    __m256 m = _mm256_castsi256_ps(_mm256_or_si256(_mm256_and_si256(bits, mantissa), one_bits));
    const __m256 big = _mm256_cmp_ps(m, f(kSqrt2), _CMP_GT_OQ);
    m = _mm256_blendv_ps(m, mul(m, f(0.5f)), big);
    e = _mm256_sub_epi32(e, _mm256_castps_si256(big));  // + 1 where big (-1 in the mask)
    const __m256 t = _mm256_div_ps(_mm256_sub_ps(m, f(1.f)), add(m, f(1.f))), t2 = mul(t, t);
    const __m256 series =
        add(f(1.f),
            mul(t2, add(f(1.f / 3),
                        mul(t2, add(f(1.f / 5), mul(t2, add(f(1.f / 7), mul(t2, f(1.f / 9)))))))));
    const __m256 ln = add(mul(_mm256_cvtepi32_ps(e), f(kLn2)), mul(add(t, t), series));
    const __m256 r = _mm256_sqrt_ps(_mm256_max_ps(mul(f(-2.f), ln), _mm256_setzero_ps()));
    const __m256 phi = mul(
        mul(_mm256_cvtepi32_ps(_mm256_and_si256(w, _mm256_set1_epi32(0x1FFFFFFF))), f(0x1p-29f)),
        f(kPiQuarter));
    const __m256 p2 = mul(phi, phi);
    const __m256 sin_phi = mul(
        phi, add(f(1.f),
                 mul(p2, add(f(-1.f / 6),
                             mul(p2, add(f(1.f / 120), mul(p2, add(f(-1.f / 5040),
                                                                   mul(p2, f(1.f / 362880))))))))));
    const __m256 cos_phi = add(
        f(1.f), mul(p2, add(f(-0.5f),
                            mul(p2, add(f(1.f / 24),
                                        mul(p2, add(f(-1.f / 720),
                                                    mul(p2, add(f(1.f / 40320),
                                                                mul(p2, f(-1.f / 3628800)))))))))));
    const __m256 swap = _mm256_castsi256_ps(_mm256_slli_epi32(w, 2));  // bit 29 as the sign
    const __m256 a = mul(r, _mm256_blendv_ps(cos_phi, sin_phi, swap));
    const __m256 b = mul(r, _mm256_blendv_ps(sin_phi, cos_phi, swap));
    const __m256i sign = _mm256_set1_epi32(static_cast<int>(0x80000000u));
    const __m256 sa = _mm256_castsi256_ps(_mm256_and_si256(w, sign));
    const __m256 sb = _mm256_castsi256_ps(_mm256_and_si256(_mm256_slli_epi32(w, 1), sign));
    _mm256_storeu_ps(dst + i, add(f(loc), mul(f(scale), _mm256_xor_ps(a, sa))));
    _mm256_storeu_ps(dst + i + 8, add(f(loc), mul(f(scale), _mm256_xor_ps(b, sb))));
  }
  rng::avx2::store_half(ga, lanes, 0);
  rng::avx2::store_half(gb, lanes, 1);
  return i;
}

template <int R>
FAULTLINE_TARGET("avx2")
std::size_t field_columns_avx2(float* col, const float* const* rows, const float* w, int radius,
                               std::size_t n) {
  const int r = R > 0 ? R : radius;
  std::size_t x = 0;
  for (; x + 8 <= n; x += 8) {
    __m256 acc = _mm256_mul_ps(_mm256_set1_ps(w[0]), _mm256_loadu_ps(rows[r] + x));
    for (int k = 1; k <= r; ++k) {
      const __m256 pair =
          _mm256_add_ps(_mm256_loadu_ps(rows[r - k] + x), _mm256_loadu_ps(rows[r + k] + x));
      acc = _mm256_add_ps(acc, _mm256_mul_ps(_mm256_set1_ps(w[k]), pair));
    }
    _mm256_storeu_ps(col + x, acc);
  }
  return x;
}

// 32 values: four blocks of 8 compared, packed to bytes (the packs interleave the 128-bit lanes:
// the dword permutation puts them back in order), 0/1.
template <int R>
FAULTLINE_TARGET("avx2")
std::size_t field_threshold_avx2(std::uint8_t* mask, const float* col, const float* w, int radius,
                                 float threshold, std::size_t n) {
  const int r = R > 0 ? R : radius;
  const __m256 t = _mm256_set1_ps(threshold);
  const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  std::size_t x = 0;
  for (; x + 32 <= n; x += 32) {
    __m256i above[4];
    for (int q = 0; q < 4; ++q) {
      const float* c = col + x + 8 * static_cast<std::size_t>(q);
      __m256 acc = _mm256_mul_ps(_mm256_set1_ps(w[0]), _mm256_loadu_ps(c));
      for (int k = 1; k <= r; ++k) {
        const __m256 pair = _mm256_add_ps(_mm256_loadu_ps(c - k), _mm256_loadu_ps(c + k));
        acc = _mm256_add_ps(acc, _mm256_mul_ps(_mm256_set1_ps(w[k]), pair));
      }
      above[q] = _mm256_castps_si256(_mm256_cmp_ps(acc, t, _CMP_GT_OQ));
    }
    const __m256i bytes = _mm256_packs_epi16(_mm256_packs_epi32(above[0], above[1]),
                                             _mm256_packs_epi32(above[2], above[3]));
    const __m256i ordered = _mm256_permutevar8x32_epi32(bytes, order);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(mask + x),
                        _mm256_and_si256(ordered, _mm256_set1_epi8(1)));
  }
  return x;
}

template <int R>
FAULTLINE_TARGET("avx2")
std::size_t level_columns_avx2(std::int16_t* col, const std::uint8_t* const* rows,
                               const std::int16_t* w, int radius, std::size_t n) {
  const int r = R > 0 ? R : radius;
  auto load = [](const std::uint8_t* p) FAULTLINE_TARGET_INLINE("avx2") {
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  };
  std::size_t x = 0;
  for (; x + 16 <= n; x += 16) {
    __m256i acc =
        _mm256_mullo_epi16(_mm256_set1_epi16(w[0]), _mm256_cvtepu8_epi16(load(rows[r] + x)));
    for (int k = 1; k <= r; ++k) {
      const __m128i pair = _mm_add_epi8(load(rows[r - k] + x), load(rows[r + k] + x));  // <= 2
      acc = _mm256_add_epi16(
          acc, _mm256_mullo_epi16(_mm256_set1_epi16(w[k]), _mm256_cvtepu8_epi16(pair)));
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(col + x), acc);
  }
  return x;
}

// The word shuffles that spread 16 per-pixel words over the 48 values of 16 BGR pixels: chunk q,
// 128-bit lane l takes its words from half (q + l + 1) / 2 of the 16 (0, 0 | 0, 1 | 1, 1).
struct SpreadShuffles {
  alignas(32) std::int8_t bytes[3][32];
  SpreadShuffles() {
    for (int q = 0; q < 3; ++q) {
      for (int l = 0; l < 2; ++l) {
        for (int j = 0; j < 8; ++j) {
          const int pixel = (16 * q + 8 * l + j) / 3;
          for (int b = 0; b < 2; ++b)
            bytes[q][16 * l + 2 * j + b] = static_cast<std::int8_t>(2 * (pixel % 8) + b);
        }
      }
    }
  }
};

// 16 pixels unchanged (inline: a memcpy call costs more than the blend it skips).
FAULTLINE_TARGET_INLINE("avx2") inline void copy48(std::uint8_t* out, const std::uint8_t* in) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out),
                      _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in)));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 32),
                   _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + 32)));
}

// The 16 levels of pixels x..x+15 (the row sums in madd pairs: the first and second halves come
// back as lanes [0-3, 8-11] and [4-7, 12-15], and packs_epi32 puts them back in order), then the
// blend of their 48 values.
template <int R>
FAULTLINE_TARGET("avx2")
std::size_t level_blend_avx2(std::uint8_t* out, const std::uint8_t* in, const std::int16_t* col,
                             const std::int16_t* w, int radius, std::size_t pixels) {
  const int r = R > 0 ? R : radius;
  static const SpreadShuffles spread;
  const __m256i cut = _mm256_set1_epi32(kMudLevelCut - 1), one = _mm256_set1_epi32(kOne + 4095);
  const __m256i below_cut = _mm256_set1_epi16(6553);  // 6553 2^15 < kMudLevelCut < 6554 2^15
  __m256i colour[3];
  for (int q = 0; q < 3; ++q) {
    alignas(32) std::int16_t c[16];
    for (int j = 0; j < 16; ++j) c[j] = static_cast<std::int16_t>(kMudColour[(16 * q + j) % 3]);
    colour[q] = _mm256_load_si256(reinterpret_cast<const __m256i*>(c));
  }
  std::size_t x = 0;
  for (; x + 16 <= pixels; x += 16) {
    const std::int16_t* c = col + x;
    auto load = [c](int k) FAULTLINE_TARGET_INLINE("avx2") {
      return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c + k));
    };
    // No column sum in reach above 0.8 (at most 6553 of 2^13): every level is below the cut.
    const __m256i reach = _mm256_max_epi16(load(-r), load(r));
    if (_mm256_movemask_epi8(_mm256_cmpgt_epi16(reach, below_cut)) == 0) {
      copy48(out + 3 * x, in + 3 * x);
      continue;
    }
    __m256i lo = _mm256_setzero_si256(), hi = _mm256_setzero_si256();
    for (int t = 0; t <= r; t += 2) {  // terms t, t + 1: the centre or a pair's sum (<= 2^14)
      const __m256i a = t == 0 ? load(0) : _mm256_add_epi16(load(-t), load(t));
      const __m256i b =
          t + 1 <= r ? _mm256_add_epi16(load(-t - 1), load(t + 1)) : _mm256_setzero_si256();
      const auto wb = static_cast<std::uint16_t>(t + 1 <= r ? w[t + 1] : 0);
      const __m256i wv = _mm256_set1_epi32(static_cast<std::int32_t>(
          static_cast<std::uint32_t>(wb) << 16 | static_cast<std::uint16_t>(w[t])));
      lo = _mm256_add_epi32(lo, _mm256_madd_epi16(_mm256_unpacklo_epi16(a, b), wv));
      hi = _mm256_add_epi32(hi, _mm256_madd_epi16(_mm256_unpackhi_epi16(a, b), wv));
    }
    const __m256i valid =
        _mm256_packs_epi32(_mm256_cmpgt_epi32(lo, cut), _mm256_cmpgt_epi32(hi, cut));
    std::uint8_t* o = out + 3 * x;
    const std::uint8_t* v8 = in + 3 * x;
    if (_mm256_movemask_epi8(valid) == 0) {
      copy48(o, v8);
      continue;
    }
    const __m256i u = _mm256_packs_epi32(_mm256_srai_epi32(_mm256_sub_epi32(one, lo), 12),
                                         _mm256_srai_epi32(_mm256_sub_epi32(one, hi), 12));
    const __m256i halves[3] = {_mm256_permute4x64_epi64(u, 0x44), u,
                               _mm256_permute4x64_epi64(u, 0xEE)};
    const __m256i valid_halves[3] = {_mm256_permute4x64_epi64(valid, 0x44), valid,
                                     _mm256_permute4x64_epi64(valid, 0xEE)};
    for (int q = 0; q < 3; ++q) {
      const __m256i shuffle = _mm256_load_si256(reinterpret_cast<const __m256i*>(spread.bytes[q]));
      const __m256i uq = _mm256_shuffle_epi8(halves[q], shuffle);
      const __m256i vq = _mm256_shuffle_epi8(valid_halves[q], shuffle);
      const __m256i v =
          _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(v8 + 16 * q)));
      const __m256i mixed =
          _mm256_add_epi16(colour[q], _mm256_mulhi_epi16(_mm256_sub_epi16(v, colour[q]), uq));
      const __m256i words = _mm256_blendv_epi8(v, mixed, vq);
      const __m128i bytes =
          _mm_packus_epi16(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(o + 16 * q), bytes);
    }
  }
  return x;
}
#endif

bool use_avx2(bool simd) { return FAULTLINE_X86_SIMD && simd && common::cpu_has_avx2(); }

void check_radius(int radius) {
  if (radius < 1 || radius > kMaxRadius) throw std::invalid_argument("spatter mud: radius 1..8");
}

}  // namespace

void mud_normals_row(float* dst, std::size_t n, float loc, float scale, rng::LaneRng& lanes,
                     bool simd) {
  std::size_t i = 0;
#if FAULTLINE_X86_SIMD
  if (use_avx2(simd)) i = normals_avx2(dst, n, loc, scale, lanes);
#endif
  std::uint32_t v[rng::LaneRng::kValuesPerStep];
  float z[rng::LaneRng::kValuesPerStep];
  for (; i < n; i += rng::LaneRng::kValuesPerStep) {
    lanes.next_values(v);
    normals_step(z, v, loc, scale);
    std::copy(z, z + std::min<std::size_t>(n - i, rng::LaneRng::kValuesPerStep), dst + i);
  }
}

void mud_field_mask_row(std::uint8_t* mask, const float* const* rows, const float* weight,
                        int radius, float threshold, float* scratch, std::size_t n, bool simd) {
  check_radius(radius);
  float* col = scratch + radius;
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (use_avx2(simd)) {
    x = radius == 3 ? field_columns_avx2<3>(col, rows, weight, radius, n)
                    : field_columns_avx2<0>(col, rows, weight, radius, n);
  }
#endif
  field_columns(col, rows, weight, radius, x, n);
  fill_border(col, radius, n);
  x = 0;
#if FAULTLINE_X86_SIMD
  if (use_avx2(simd)) {
    x = radius == 3 ? field_threshold_avx2<3>(mask, col, weight, radius, threshold, n)
                    : field_threshold_avx2<0>(mask, col, weight, radius, threshold, n);
  }
#endif
  field_threshold(mask, col, weight, radius, threshold, x, n);
}

void mud_level_blend_row(std::uint8_t* out, const std::uint8_t* in, const std::uint8_t* const* rows,
                         const std::int16_t* column, const std::int16_t* row, int radius,
                         std::int16_t* scratch, std::size_t pixels, bool simd) {
  check_radius(radius);
  std::int16_t* col = scratch + radius;
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (use_avx2(simd)) {
    x = radius == 6 ? level_columns_avx2<6>(col, rows, column, radius, pixels)
                    : level_columns_avx2<0>(col, rows, column, radius, pixels);
  }
#endif
  level_columns(col, rows, column, radius, x, pixels);
  fill_border(col, radius, pixels);
  x = 0;
#if FAULTLINE_X86_SIMD
  if (use_avx2(simd)) {
    x = radius == 6 ? level_blend_avx2<6>(out, in, col, row, radius, pixels)
                    : level_blend_avx2<0>(out, in, col, row, radius, pixels);
  }
#endif
  level_blend(out, in, col, row, radius, x, pixels);
}

}  // namespace detail

namespace {

// OpenCV's Gaussian for float32 (getGaussianKernel), offsets 0..radius.
std::vector<float> field_weights(double sigma, int radius) {
  const cv::Mat k = cv::getGaussianKernel(2 * radius + 1, sigma, CV_32F);
  std::vector<float> w(static_cast<std::size_t>(radius) + 1);
  for (int i = 0; i <= radius; ++i) w[static_cast<std::size_t>(i)] = k.at<float>(radius + i);
  return w;
}

// The same (in float64) in fixed point with `bits` fraction bits, the centre taking the rounding
// remainder (the weights sum to exactly 2^bits).
std::vector<std::int16_t> level_weights(double sigma, int radius, int bits) {
  const cv::Mat k = cv::getGaussianKernel(2 * radius + 1, sigma, CV_64F);
  std::vector<double> half(static_cast<std::size_t>(radius) + 1);
  for (int i = 0; i <= radius; ++i) half[static_cast<std::size_t>(i)] = k.at<double>(radius + i);
  return fixed_point_kernel(half, bits).weight;
}

// Rings of 2 r + 1 rows (the normals for the field's blur, the mask for the mask's) and the
// rows' scratch, kept per thread.
struct MudScratch {
  std::vector<float> normals, field_scratch;
  std::vector<std::uint8_t> mask;
  std::vector<std::int16_t> level_scratch;
  void resize(std::size_t n, int rf, int rm) {
    normals.resize(static_cast<std::size_t>(2 * rf + 1) * n);
    field_scratch.resize(n + 2 * static_cast<std::size_t>(rf));
    mask.resize(static_cast<std::size_t>(2 * rm + 1) * n);
    level_scratch.resize(n + 2 * static_cast<std::size_t>(rm));
  }
};

}  // namespace

cv::Mat mud_blend_fast(const cv::Mat& bgr, const SpatterParams& p, rng::FastRng& rng) {
  const int rows = bgr.rows;
  const auto n = static_cast<std::size_t>(bgr.cols);
  const int rf = static_cast<int>(std::ceil(3.0 * p.sigma));
  const int rm = (cvRound(p.intensity * 8 + 1) | 1) / 2;  // OpenCV's size for float: 13 at 1.5
  if (rf > detail::kMaxRadius || rm > detail::kMaxRadius)
    throw std::invalid_argument("spatter mud: sigma too large");
  const std::vector<float> wf = field_weights(p.sigma, rf);
  const std::vector<std::int16_t> column = level_weights(p.intensity, rm, 13);
  const std::vector<std::int16_t> row = level_weights(p.intensity, rm, 15);
  thread_local MudScratch s;
  s.resize(n, rf, rm);
  auto clamp_row = [rows](int y) { return std::min(std::max(y, 0), rows - 1); };
  auto normal_row = [&](int y) { return s.normals.data() + (clamp_row(y) % (2 * rf + 1)) * n; };
  auto mask_row = [&](int y) { return s.mask.data() + (clamp_row(y) % (2 * rm + 1)) * n; };
  rng::LaneRng lanes(rng);
  const auto threshold = static_cast<float>(p.threshold);
  const auto loc = static_cast<float>(p.loc), scale = static_cast<float>(p.scale);
  int normals_done = 0, masks_done = 0;
  auto next_mask_row = [&] {
    const int y = masks_done++;
    for (; normals_done <= std::min(y + rf, rows - 1); ++normals_done)
      detail::mud_normals_row(normal_row(normals_done), n, loc, scale, lanes, true);
    const float* src[2 * detail::kMaxRadius + 1];
    for (int k = -rf; k <= rf; ++k) src[k + rf] = normal_row(y + k);
    detail::mud_field_mask_row(mask_row(y), src, wf.data(), rf, threshold, s.field_scratch.data(),
                               n, true);
  };
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < rows; ++y) {
    while (masks_done <= std::min(y + rm, rows - 1)) next_mask_row();
    const std::uint8_t* src[2 * detail::kMaxRadius + 1];
    for (int k = -rm; k <= rm; ++k) src[k + rm] = mask_row(y + k);
    detail::mud_level_blend_row(out.ptr<std::uint8_t>(y), bgr.ptr<std::uint8_t>(y), src,
                                column.data(), row.data(), rm, s.level_scratch.data(), n, true);
  }
  return out;
}

}  // namespace faultline::corruption
