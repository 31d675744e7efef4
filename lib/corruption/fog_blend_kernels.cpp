// Fog blend row kernels: the exact, float32 and fixed-point blends, the image maximum and the fast
// field's upsampling. AVX2 intrinsics bodies (no FMA: every product is rounded before its sum, like
// NumPy) and the scalar bodies they must equal bit for bit. The library is compiled with
// -ffp-contract=off.
#include <algorithm>
#include <array>
#include <cstring>

#include "common/simd.hpp"
#include "corruption/fog_kernels.hpp"
#include "rng/lane_rng_avx2.hpp"

namespace faultline::corruption {
namespace {

// k / 255.0 for every byte: the reference's x = u8 / 255 without a division per value.
const std::array<double, 256>& inv255_table() {
  static const std::array<double, 256> table = [] {
    std::array<double, 256> t{};
    for (int k = 0; k < 256; ++k) t[static_cast<std::size_t>(k)] = k / 255.0;
    return t;
  }();
  return table;
}

// The reference's expression for one value: byte k of a pixel whose raw fractal value is p.
inline std::uint8_t exact_value(std::uint8_t k, double p, const FogBlendExact& b) {
  const double f = (p - b.min) / b.range;
  const double add = b.strength * f;
  const double v = inv255_table()[k] + add;
  const double r = (v * b.m) / b.denom;
  return static_cast<std::uint8_t>(std::min(std::max(r, 0.0), 1.0) * 255.0);
}
// Pixels [x, cols) with raw values raw(x).
template <typename Raw>
void blend_exact_scalar(const std::uint8_t* src, std::uint8_t* dst, int x, int cols,
                        const FogBlendExact& b, Raw raw) {
  for (; x < cols; ++x) {
    const double p = raw(x);
    for (int c = 0; c < 3; ++c) dst[3 * x + c] = exact_value(src[3 * x + c], p, b);
  }
}
void upsample4_scalar(const float* low, float* out, int x, int count) {
  for (; x < count; ++x) {
    const int c = x / 4;
    const float t = static_cast<float>(x % 4) * 0.25f;
    out[x] = x % 4 == 0 ? low[c] : low[c] * (1.0f - t) + low[c + 1] * t;
  }
}
// Pixels [x, cols) with field values field(x).
template <typename Field>
void blend_fast_scalar(const std::uint8_t* src, std::uint8_t* dst, int x, int cols, float scale,
                       float add_scale, Field field) {
  for (; x < cols; ++x) {
    const float a = add_scale * field(x);
    for (int c = 0; c < 3; ++c) {
      const float v = static_cast<float>(src[3 * x + c]) * scale + a;
      dst[3 * x + c] =
          static_cast<std::uint8_t>(static_cast<int>(std::min(std::max(v, 0.0f), 255.0f)));
    }
  }
}
void blend_fast_scalar(const std::uint8_t* src, const float* f, std::uint8_t* dst, int x, int cols,
                       float scale, float add_scale) {
  blend_fast_scalar(src, dst, x, cols, scale, add_scale, [f](int i) { return f[i]; });
}
void blend_fast_lerp_scalar(const std::uint8_t* src, const float* fa, const float* fb,
                            std::uint8_t* dst, int x, int cols, float wa, float wb, float scale,
                            float add_scale) {
  blend_fast_scalar(src, dst, x, cols, scale, add_scale,
                    [=](int i) { return fa[i] * wa + fb[i] * wb; });
}
std::uint8_t max_u8_scalar(const std::uint8_t* p, std::size_t count, std::uint8_t mx) {
  for (std::size_t i = 0; i < count; ++i) mx = std::max(mx, p[i]);
  return mx;
}
// Fixed-point fast blend (8 fraction bits): g = trunc(f * add256 + 1) (round to nearest, plus half
// a unit that offsets the product's truncation below), the vertical lerp by rounding averages, out
// = (((src << 8) * scale16)
// >> 16 + g) >> 8, saturating at 255.
void fixed_field_scalar(const float* f, std::uint16_t* g, int x, int cols, float add256) {
  for (; x < cols; ++x) {
    const int v = std::min(static_cast<int>(f[x] * add256 + 0.5f), 65535);
    for (int c = 0; c < 3; ++c) g[3 * x + c] = static_cast<std::uint16_t>(v);
  }
}
inline unsigned avg_u16(unsigned a, unsigned b) { return (a + b + 1) >> 1; }
inline unsigned lerp_u16(unsigned a, unsigned b, int k) {
  switch (k) {
    case 0:
      return a;
    case 1:
      return avg_u16(avg_u16(a, b), a);
    case 2:
      return avg_u16(a, b);
    default:
      return avg_u16(avg_u16(a, b), b);
  }
}
void blend_fixed_scalar(const std::uint8_t* src, const std::uint16_t* ga, const std::uint16_t* gb,
                        int k, std::uint8_t* dst, int i, int count, std::uint16_t scale16) {
  for (; i < count; ++i) {
    const unsigned p = ((static_cast<unsigned>(src[i]) << 8) * scale16) >> 16;
    const unsigned v = std::min(p + lerp_u16(ga[i], k ? gb[i] : ga[i], k), 65535u);
    dst[i] = static_cast<std::uint8_t>(v >> 8);
  }
}

#if FAULTLINE_X86_SIMD

// The exact blend without a division. With d = p - min (the reference's double), the ideal value is
// Y = k * A + d * K, A = m / denom, K = 255 * m * a / (denom * range), all terms >= 0; the
// reference's y = fl(fl(fl(fl(k / 255) + a * fl(d / range)) * m) / denom) * 255 is within 1e-12 of
// Y. The float32 candidate y' = k * float(A) + float(d * K) is within 3.2 * 2^-24 * 255 < 5e-5 of Y
// (two roundings on the product, one on the term, one on the sum). So wherever no integer lies in
// [y' - kNear, y' + kNear] (kNear = 2^-12, five times the error, and far above the float rounding
// of y' +- kNear), trunc(y') is the reference's byte (clip included: y <= 255 unless r > 1, and
// packus saturates at 255). Flagged values (about 2 * 24 * 2^-12 per 8 pixels) are recomputed by
// the reference's expression.
constexpr float kNear = 1.0f / 4096.0f;

struct BlendVec {
  __m256d min, k;
  __m256 a;
};

// Eight pixels with raw values r0 (pixels 0..3) and r1 (4..7); returns the mask of values to
// recompute (bit t of channel vector c is value 8c + t).
FAULTLINE_TARGET_INLINE("avx2")
inline std::uint32_t blend8(const std::uint8_t* s, std::uint8_t* d, __m256d r0, __m256d r1,
                            const BlendVec& v) {
  const __m128 b0 = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(r0, v.min), v.k));
  const __m128 b1 = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(r1, v.min), v.k));
  const __m256 bias = _mm256_set_m128(b1, b0);
  const __m256 near = _mm256_set1_ps(kNear);
  __m256i lo[3];
  std::uint32_t flagged = 0;
  static constexpr int kSpread[3][8] = {
      {0, 0, 0, 1, 1, 1, 2, 2}, {2, 3, 3, 3, 4, 4, 4, 5}, {5, 5, 6, 6, 6, 7, 7, 7}};
  for (int c = 0; c < 3; ++c) {
    const __m256 add = _mm256_permutevar8x32_ps(
        bias, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kSpread[c])));
    const __m256i k =
        _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(s + 8 * c)));
    const __m256 y = _mm256_add_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(k), v.a), add);
    lo[c] = _mm256_cvttps_epi32(_mm256_sub_ps(y, near));
    const __m256i hi = _mm256_cvttps_epi32(_mm256_add_ps(y, near));
    const auto same = static_cast<std::uint32_t>(
        _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(lo[c], hi))));
    flagged |= (~same & 0xFFu) << (8 * c);
  }
  // packs work per 128-bit lane: fix the order with 64-bit permutes (negative lo of -kNear packs to
  // 0).
  const __m256i w01 = _mm256_permute4x64_epi64(_mm256_packs_epi32(lo[0], lo[1]), 0xD8);
  const __m256i w2 = _mm256_permute4x64_epi64(_mm256_packs_epi32(lo[2], lo[2]), 0xD8);
  const __m256i bytes = _mm256_permute4x64_epi64(_mm256_packus_epi16(w01, w2), 0xD8);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(d), _mm256_castsi256_si128(bytes));
  _mm_storel_epi64(reinterpret_cast<__m128i*>(d + 16), _mm256_extracti128_si256(bytes, 1));
  return flagged;
}

FAULTLINE_TARGET_INLINE("avx2") inline BlendVec blend_vec(const FogBlendExact& b) {
  const double a = b.m / b.denom;
  const double k = (255.0 * b.m * b.strength) / (b.denom * b.range);
  return {_mm256_set1_pd(b.min), _mm256_set1_pd(k), _mm256_set1_ps(static_cast<float>(a))};
}

inline void fix_flagged(const std::uint8_t* s, std::uint8_t* d, const double* raw8,
                        std::uint32_t flagged, const FogBlendExact& b) {
  while (flagged != 0) {
    const int t = __builtin_ctz(flagged);
    flagged &= flagged - 1;
    d[t] = exact_value(s[t], raw8[t / 3], b);
  }
}

FAULTLINE_TARGET("avx2")
void blend_exact_avx2(const std::uint8_t* src, const double* f, std::uint8_t* dst, int cols,
                      const FogBlendExact& b) {
  const BlendVec v = blend_vec(b);
  int x = 0;
  for (; x + 8 <= cols; x += 8) {
    const std::uint32_t flagged =
        blend8(src + 3 * x, dst + 3 * x, _mm256_loadu_pd(f + x), _mm256_loadu_pd(f + x + 4), v);
    if (flagged != 0) fix_flagged(src + 3 * x, dst + 3 * x, f + x, flagged, b);
  }
  blend_exact_scalar(src, dst, x, cols, b, [f](int i) { return f[i]; });
}

FAULTLINE_TARGET("avx2")
void blend_exact_pairs_avx2(const std::uint8_t* src, const double* even, const double* odd,
                            std::uint8_t* dst, int cols, const FogBlendExact& b) {
  const BlendVec v = blend_vec(b);
  int x = 0;
  for (; x + 8 <= cols; x += 8) {
    const __m256d e = _mm256_loadu_pd(even + x / 2), o = _mm256_loadu_pd(odd + x / 2);
    const __m256d lo = _mm256_unpacklo_pd(e, o),
                  hi = _mm256_unpackhi_pd(e, o);  // e0 o0 e2 o2 | e1 o1 e3 o3
    const __m256d r0 = _mm256_permute2f128_pd(lo, hi, 0x20),
                  r1 = _mm256_permute2f128_pd(lo, hi, 0x31);
    const std::uint32_t flagged = blend8(src + 3 * x, dst + 3 * x, r0, r1, v);
    if (flagged != 0) {
      alignas(32) double raw[8];
      _mm256_store_pd(raw, r0);
      _mm256_store_pd(raw + 4, r1);
      fix_flagged(src + 3 * x, dst + 3 * x, raw, flagged, b);
    }
  }
  blend_exact_scalar(src, dst, x, cols, b,
                     [even, odd](int i) { return i % 2 ? odd[i / 2] : even[i / 2]; });
}

// trunc(src * scale + add) for eight bytes, as int32. No clamps: scale, add >= 0 keep v >= 0 and v
// stays far below 2^31, and the caller's saturating packs turn every v >= 255 into 255, as clamping
// first would.
FAULTLINE_TARGET_INLINE("avx2")
inline __m256i fast_channel(const std::uint8_t* s, __m256 add, __m256 vscale) {
  const __m256i b = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(s)));
  return _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(b), vscale), add));
}

// Eight pixels (24 values) per step; field(x) loads the field values of pixels x .. x + 7.
template <typename Field>
FAULTLINE_TARGET_INLINE("avx2")
inline void blend_fast_body(const std::uint8_t* src, std::uint8_t* dst, int cols, float scale,
                            float add_scale, Field field, int* done) {
  const __m256 vscale = _mm256_set1_ps(scale), vadd = _mm256_set1_ps(add_scale);
  const __m256i p0 = _mm256_setr_epi32(0, 0, 0, 1, 1, 1, 2, 2);
  const __m256i p1 = _mm256_setr_epi32(2, 3, 3, 3, 4, 4, 4, 5);
  const __m256i p2 = _mm256_setr_epi32(5, 5, 6, 6, 6, 7, 7, 7);
  int x = 0;
  for (; x + 8 <= cols; x += 8) {
    const std::uint8_t* s = src + 3 * x;
    const __m256 a = _mm256_mul_ps(vadd, field(x));
    const __m256i i0 = fast_channel(s, _mm256_permutevar8x32_ps(a, p0), vscale);
    const __m256i i1 = fast_channel(s + 8, _mm256_permutevar8x32_ps(a, p1), vscale);
    const __m256i i2 = fast_channel(s + 16, _mm256_permutevar8x32_ps(a, p2), vscale);
    // packs work per 128-bit lane: fix the order with 64-bit permutes.
    const __m256i w01 =
        _mm256_permute4x64_epi64(_mm256_packs_epi32(i0, i1), 0xD8);  // 16 x int16, in order
    const __m256i w2 =
        _mm256_permute4x64_epi64(_mm256_packs_epi32(i2, i2), 0xD8);  // 8 x int16 twice
    const __m256i b =
        _mm256_permute4x64_epi64(_mm256_packus_epi16(w01, w2), 0xD8);  // 24 bytes in order
    std::uint8_t* d = dst + 3 * x;
    _mm_storeu_si128(reinterpret_cast<__m128i*>(d), _mm256_castsi256_si128(b));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(d + 16), _mm256_extracti128_si256(b, 1));
  }
  *done = x;
}

FAULTLINE_TARGET("avx2")
void blend_fast_avx2(const std::uint8_t* src, const float* f, std::uint8_t* dst, int cols,
                     float scale, float add_scale) {
  int x = 0;
  blend_fast_body(
      src, dst, cols, scale, add_scale,
      [f](int i) FAULTLINE_TARGET_INLINE("avx2") { return _mm256_loadu_ps(f + i); }, &x);
  blend_fast_scalar(src, f, dst, x, cols, scale, add_scale);
}

// The field row as fa * wa + fb * wb (two products, then the sum: lerp_avx2's rounding), never
// stored.
FAULTLINE_TARGET("avx2")
void blend_fast_lerp_avx2(const std::uint8_t* src, const float* fa, const float* fb,
                          std::uint8_t* dst, int cols, float wa, float wb, float scale,
                          float add_scale) {
  const __m256 va = _mm256_set1_ps(wa), vb = _mm256_set1_ps(wb);
  int x = 0;
  blend_fast_body(
      src, dst, cols, scale, add_scale,
      [=](int i) FAULTLINE_TARGET_INLINE("avx2") {
        return _mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(fa + i), va),
                             _mm256_mul_ps(_mm256_loadu_ps(fb + i), vb));
      },
      &x);
  blend_fast_lerp_scalar(src, fa, fb, dst, x, cols, wa, wb, scale, add_scale);
}

// Byte maximum, 128 bytes per step; stops at the first 4 KB block that reaches 255 (nothing is
// larger).
FAULTLINE_TARGET("avx2")
std::uint8_t max_u8_avx2(const std::uint8_t* p, std::size_t count, std::uint8_t mx) {
  const __m256i all = _mm256_set1_epi8(static_cast<char>(0xFF));
  __m256i m = _mm256_set1_epi8(static_cast<char>(mx));
  std::size_t i = 0;
  while (i + 128 <= count) {
    const std::size_t end = std::min(count - count % 128, i + 4096);
    __m256i m0 = m, m1 = m, m2 = m, m3 = m;
    for (; i < end; i += 128) {
      const auto* v = reinterpret_cast<const __m256i*>(p + i);
      m0 = _mm256_max_epu8(m0, _mm256_loadu_si256(v));
      m1 = _mm256_max_epu8(m1, _mm256_loadu_si256(v + 1));
      m2 = _mm256_max_epu8(m2, _mm256_loadu_si256(v + 2));
      m3 = _mm256_max_epu8(m3, _mm256_loadu_si256(v + 3));
    }
    m = _mm256_max_epu8(_mm256_max_epu8(m0, m1), _mm256_max_epu8(m2, m3));
    if (_mm256_movemask_epi8(_mm256_cmpeq_epi8(m, all)) != 0) return 0xFF;
  }
  alignas(32) std::uint8_t lanes[32];
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), m);
  for (std::uint8_t v : lanes) mx = std::max(mx, v);
  return max_u8_scalar(p + i, count - i, mx);
}

// Eight field values -> 24 fixed-point values (each tripled for the three channels).
FAULTLINE_TARGET("avx2")
void fixed_field_avx2(const float* f, std::uint16_t* g, int cols, float add256) {
  const __m256 vmul = _mm256_set1_ps(add256), one = _mm256_set1_ps(0.5f);
  const __m128i t0 = _mm_setr_epi8(0, 1, 0, 1, 0, 1, 2, 3, 2, 3, 2, 3, 4, 5, 4, 5);
  const __m128i t1 = _mm_setr_epi8(4, 5, 6, 7, 6, 7, 6, 7, 8, 9, 8, 9, 8, 9, 10, 11);
  const __m128i t2 = _mm_setr_epi8(10, 11, 10, 11, 12, 13, 12, 13, 12, 13, 14, 15, 14, 15, 14, 15);
  int x = 0;
  for (; x + 8 <= cols; x += 8) {
    const __m256i v =
        _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(f + x), vmul), one));
    const __m128i w =
        _mm256_castsi256_si128(_mm256_permute4x64_epi64(_mm256_packus_epi32(v, v), 0x08));
    auto* o = reinterpret_cast<__m128i*>(g + 3 * x);
    _mm_storeu_si128(o, _mm_shuffle_epi8(w, t0));
    _mm_storeu_si128(o + 1, _mm_shuffle_epi8(w, t1));
    _mm_storeu_si128(o + 2, _mm_shuffle_epi8(w, t2));
  }
  fixed_field_scalar(f, g, x, cols, add256);
}

template <int K>
FAULTLINE_TARGET_INLINE("avx2")
inline __m256i fixed_lerp(const std::uint16_t* ga, const std::uint16_t* gb) {
  const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(ga));
  if constexpr (K == 0) {
    return a;
  } else {
    const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(gb));
    const __m256i mid = _mm256_avg_epu16(a, b);
    if constexpr (K == 1) return _mm256_avg_epu16(mid, a);
    if constexpr (K == 2) return mid;
    return _mm256_avg_epu16(mid, b);
  }
}
// 16 values: ((src << 8) * scale16 >> 16 + g) >> 8, as 16-bit lanes.
template <int K>
FAULTLINE_TARGET_INLINE("avx2")
inline __m256i fixed_half(const std::uint8_t* s, const std::uint16_t* ga, const std::uint16_t* gb,
                          __m256i vscale) {
  const __m256i x = _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s)));
  const __m256i p = _mm256_mulhi_epu16(_mm256_slli_epi16(x, 8), vscale);
  return _mm256_srli_epi16(_mm256_adds_epu16(p, fixed_lerp<K>(ga, gb)), 8);
}
template <int K>
FAULTLINE_TARGET("avx2")
void blend_fixed_avx2(const std::uint8_t* src, const std::uint16_t* ga, const std::uint16_t* gb,
                      std::uint8_t* dst, int count, std::uint16_t scale16) {
  const __m256i vscale = _mm256_set1_epi16(static_cast<short>(scale16));
  int i = 0;
  for (; i + 32 <= count; i += 32) {
    const __m256i lo = fixed_half<K>(src + i, ga + i, gb + i, vscale);
    const __m256i hi = fixed_half<K>(src + i + 16, ga + i + 16, gb + i + 16, vscale);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + i),
                        _mm256_permute4x64_epi64(_mm256_packus_epi16(lo, hi), 0xD8));
  }
  blend_fixed_scalar(src, ga, gb, K, dst, i, count, scale16);
}

// Eight low values -> 32 outputs: the four phases as vectors, then a 4 x 8 transpose.
FAULTLINE_TARGET("avx2") void upsample4_avx2(const float* low, float* out, int count) {
  const __m256 w1 = _mm256_set1_ps(0.25f), w2 = _mm256_set1_ps(0.5f), w3 = _mm256_set1_ps(0.75f);
  int c = 0;
  for (; 4 * c + 32 <= count; c += 8) {
    const __m256 a = _mm256_loadu_ps(low + c), b = _mm256_loadu_ps(low + c + 1);
    const __m256 v0 = a;
    const __m256 v1 = _mm256_add_ps(_mm256_mul_ps(a, w3), _mm256_mul_ps(b, w1));
    const __m256 v2 = _mm256_add_ps(_mm256_mul_ps(a, w2), _mm256_mul_ps(b, w2));
    const __m256 v3 = _mm256_add_ps(_mm256_mul_ps(a, w1), _mm256_mul_ps(b, w3));
    const __m256d t01lo =
        _mm256_castps_pd(_mm256_unpacklo_ps(v0, v1));  // (c0: t0 t1, c1: t0 t1 | c4, c5)
    const __m256d t01hi = _mm256_castps_pd(_mm256_unpackhi_ps(v0, v1));  // (c2, c3 | c6, c7)
    const __m256d t23lo = _mm256_castps_pd(_mm256_unpacklo_ps(v2, v3));
    const __m256d t23hi = _mm256_castps_pd(_mm256_unpackhi_ps(v2, v3));
    const __m256 q0 =
        _mm256_castpd_ps(_mm256_unpacklo_pd(t01lo, t23lo));  // c0 | c4, all four phases
    const __m256 q1 = _mm256_castpd_ps(_mm256_unpackhi_pd(t01lo, t23lo));  // c1 | c5
    const __m256 q2 = _mm256_castpd_ps(_mm256_unpacklo_pd(t01hi, t23hi));  // c2 | c6
    const __m256 q3 = _mm256_castpd_ps(_mm256_unpackhi_pd(t01hi, t23hi));  // c3 | c7
    float* o = out + 4 * c;
    _mm256_storeu_ps(o, _mm256_permute2f128_ps(q0, q1, 0x20));
    _mm256_storeu_ps(o + 8, _mm256_permute2f128_ps(q2, q3, 0x20));
    _mm256_storeu_ps(o + 16, _mm256_permute2f128_ps(q0, q1, 0x31));
    _mm256_storeu_ps(o + 24, _mm256_permute2f128_ps(q2, q3, 0x31));
  }
  upsample4_scalar(low, out, 4 * c, count);
}

FAULTLINE_TARGET("avx2")
void lerp_avx2(const float* a, const float* b, float* out, int count, float wa, float wb) {
  const __m256 va = _mm256_set1_ps(wa), vb = _mm256_set1_ps(wb);
  int j = 0;
  for (; j + 8 <= count; j += 8) {
    _mm256_storeu_ps(out + j, _mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(a + j), va),
                                            _mm256_mul_ps(_mm256_loadu_ps(b + j), vb)));
  }
  for (; j < count; ++j) out[j] = a[j] * wa + b[j] * wb;
}

#endif

}  // namespace

void fog_blend_exact_row(const std::uint8_t* src, const double* f, std::uint8_t* dst, int cols,
                         const FogBlendExact& b) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return blend_exact_avx2(src, f, dst, cols, b);
#endif
  blend_exact_scalar(src, dst, 0, cols, b, [f](int i) { return f[i]; });
}

void fog_blend_exact_pairs(const std::uint8_t* src, const double* even, const double* odd,
                           std::uint8_t* dst, int cols, const FogBlendExact& b) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return blend_exact_pairs_avx2(src, even, odd, dst, cols, b);
#endif
  blend_exact_scalar(src, dst, 0, cols, b,
                     [even, odd](int i) { return i % 2 ? odd[i / 2] : even[i / 2]; });
}

void fog_blend_fast_row(const std::uint8_t* src, const float* f, std::uint8_t* dst, int cols,
                        float scale, float add_scale) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return blend_fast_avx2(src, f, dst, cols, scale, add_scale);
#endif
  blend_fast_scalar(src, f, dst, 0, cols, scale, add_scale);
}

void fog_blend_fast_lerp_row(const std::uint8_t* src, const float* fa, const float* fb,
                             std::uint8_t* dst, int cols, float wa, float wb, float scale,
                             float add_scale) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2())
    return blend_fast_lerp_avx2(src, fa, fb, dst, cols, wa, wb, scale, add_scale);
#endif
  blend_fast_lerp_scalar(src, fa, fb, dst, 0, cols, wa, wb, scale, add_scale);
}

std::uint8_t fog_max_u8(const std::uint8_t* p, std::size_t count, std::uint8_t mx) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return max_u8_avx2(p, count, mx);
#endif
  return max_u8_scalar(p, count, mx);
}

void fog_fixed_field_row(const float* f, std::uint16_t* g, int cols, float add_scale) {
  const float add256 = add_scale * 256.0f;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return fixed_field_avx2(f, g, cols, add256);
#endif
  fixed_field_scalar(f, g, 0, cols, add256);
}

void fog_blend_fixed_row(const std::uint8_t* src, const std::uint16_t* ga, const std::uint16_t* gb,
                         int k, std::uint8_t* dst, int cols, std::uint16_t scale16) {
  const int count = 3 * cols;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) {
    switch (k) {
      case 0:
        return blend_fixed_avx2<0>(src, ga, gb, dst, count, scale16);
      case 1:
        return blend_fixed_avx2<1>(src, ga, gb, dst, count, scale16);
      case 2:
        return blend_fixed_avx2<2>(src, ga, gb, dst, count, scale16);
      default:
        return blend_fixed_avx2<3>(src, ga, gb, dst, count, scale16);
    }
  }
#endif
  blend_fixed_scalar(src, ga, gb, k, dst, 0, count, scale16);
}

void fog_upsample4_row(const float* low, float* out, int count) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return upsample4_avx2(low, out, count);
#endif
  upsample4_scalar(low, out, 0, count);
}

void fog_lerp_row(const float* a, const float* b, float* out, int count, float wa, float wb) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return lerp_avx2(a, b, out, count, wa, wb);
#endif
  for (int j = 0; j < count; ++j) out[j] = a[j] * wa + b[j] * wb;
}

}  // namespace faultline::corruption
