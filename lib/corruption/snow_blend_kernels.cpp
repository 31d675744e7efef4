// Snow whitening blend loops (fast and exact). The AVX2 bodies run whole blocks and the scalar
// bodies (same arithmetic, same rounding) the rest.
#include <algorithm>
#include <cmath>

#include "common/simd.hpp"
#include "corruption/snow_kernels.hpp"

namespace faultline::corruption::snow_kernels {
namespace {

// The fast blend's fixed-point constants: values carry 6 fraction bits (x64); products are (x * k)
// >> 16 with the multiplicand scaled to use the 16 bits.
struct BlendFixed {
  static constexpr std::uint32_t kGrey0 = 7348, kGrey1 = 14426,
                                 kGrey2 = 2802;         // 1.5 * (0.299, 0.587, 0.114) * 2^14
  static constexpr std::uint32_t kBrightOffset = 8160;  // 127.5 * 64
  std::uint32_t b14, one_minus_b15;                     // b * 2^14, (1 - b) * 2^15
  BlendFixed(float b, float one_minus_b)
      : b14(static_cast<std::uint32_t>(std::lround(b * 16384.0f))),
        one_minus_b15(static_cast<std::uint32_t>(std::lround(one_minus_b * 32768.0f))) {}
};

void blend_scalar(const std::uint8_t* src, const std::uint8_t* layer, const std::uint8_t* rot,
                  bool rot_reversed, std::uint8_t* dst, int x0, int cols, const BlendFixed& f) {
  for (int x = x0; x < cols; ++x) {
    const std::uint32_t c8[3] = {std::uint32_t{src[3 * x]} << 8, std::uint32_t{src[3 * x + 1]} << 8,
                                 std::uint32_t{src[3 * x + 2]} << 8};
    const std::uint32_t bright = ((c8[0] * BlendFixed::kGrey0) >> 16) +
                                 ((c8[1] * BlendFixed::kGrey1) >> 16) +
                                 ((c8[2] * BlendFixed::kGrey2) >> 16) + BlendFixed::kBrightOffset;
    const std::uint32_t snow =
        (std::uint32_t{layer[x]} + (rot_reversed ? rot[cols - 1 - x] : rot[x])) << 6;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t m = std::max(c8[k] >> 2, bright);
      const std::uint32_t v = ((c8[k] * f.b14) >> 16) + (((m << 1) * f.one_minus_b15) >> 16) + snow;
      dst[3 * x + k] = static_cast<std::uint8_t>(std::min<std::uint32_t>(255, v >> 6));
    }
  }
}

#if FAULTLINE_X86_SIMD

// pshufb masks: planar <-> interleaved for 16 three-byte pixels held in three 16-byte blocks.
struct Shuffles {
  alignas(16) std::int8_t split[3][3][16];  // [plane][block]: bytes of `plane` taken from `block`
  alignas(16) std::int8_t merge[3][3][16];  // [block][plane]: bytes of `block` taken from `plane`
  Shuffles() {
    for (int k = 0; k < 3; ++k) {
      for (int blk = 0; blk < 3; ++blk) {
        for (int j = 0; j < 16; ++j) {
          const int g = 3 * j + k;  // interleaved position of pixel j, plane k
          split[k][blk][j] = static_cast<std::int8_t>(g / 16 == blk ? g % 16 : -128);
          const int h = 16 * blk + j;  // interleaved position in block blk
          merge[blk][k][j] = static_cast<std::int8_t>(h % 3 == k ? h / 3 : -128);
        }
      }
    }
  }
};
const Shuffles& shuffles() {
  static const Shuffles s;
  return s;
}

FAULTLINE_TARGET("avx2") inline __m128i mask(const std::int8_t* m) {
  return _mm_load_si128(reinterpret_cast<const __m128i*>(m));
}

// Two vectors of eight int32 in 0..255 -> sixteen bytes.
FAULTLINE_TARGET("avx2") inline __m128i narrow(__m256i lo, __m256i hi) {
  const __m256i words = _mm256_permute4x64_epi64(_mm256_packus_epi32(lo, hi), 0xD8);
  return _mm_packus_epi16(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
}

// The 16 BGR pixels at x split into B, G and R planes.
FAULTLINE_TARGET("avx2")
inline void load_planes(const Shuffles& m, const std::uint8_t* src, int x, __m128i plane[3]) {
  __m128i blk[3];
  for (int i = 0; i < 3; ++i)
    blk[i] = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + 3 * x + 16 * i));
  for (int k = 0; k < 3; ++k) {
    plane[k] = _mm_or_si128(_mm_or_si128(_mm_shuffle_epi8(blk[0], mask(m.split[k][0])),
                                         _mm_shuffle_epi8(blk[1], mask(m.split[k][1]))),
                            _mm_shuffle_epi8(blk[2], mask(m.split[k][2])));
  }
}

// The rotated layer's 16 bytes for pixels x..x+15: read backwards from the end of the row when
// rot_reversed.
FAULTLINE_TARGET("avx2")
inline __m128i load_rotated(const std::uint8_t* rot, bool rot_reversed, int cols, int x) {
  const __m128i reverse = _mm_setr_epi8(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0);
  return rot_reversed
             ? _mm_shuffle_epi8(
                   _mm_loadu_si128(reinterpret_cast<const __m128i*>(rot + cols - 16 - x)), reverse)
             : _mm_loadu_si128(reinterpret_cast<const __m128i*>(rot + x));
}

// B, G and R planes of 16 bytes -> 16 interleaved BGR pixels at x.
FAULTLINE_TARGET("avx2")
inline void merge_planes(const Shuffles& m, const __m128i res[3], std::uint8_t* dst, int x) {
  for (int i = 0; i < 3; ++i) {
    const __m128i v = _mm_or_si128(_mm_or_si128(_mm_shuffle_epi8(res[0], mask(m.merge[i][0])),
                                                _mm_shuffle_epi8(res[1], mask(m.merge[i][1]))),
                                   _mm_shuffle_epi8(res[2], mask(m.merge[i][2])));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + 3 * x + 16 * i), v);
  }
}

// Per plane two vectors of eight int32 in 0..255 -> 16 interleaved BGR pixels at x.
FAULTLINE_TARGET("avx2")
inline void store_planes(const Shuffles& m, const __m256i out[3][2], std::uint8_t* dst, int x) {
  __m128i res[3];
  for (int k = 0; k < 3; ++k) res[k] = narrow(out[k][0], out[k][1]);
  merge_planes(m, res, dst, x);
}

FAULTLINE_TARGET("avx2") inline __m256i set16(std::uint32_t v) {
  return _mm256_set1_epi16(static_cast<short>(static_cast<std::uint16_t>(v)));
}

// Whole blocks of 16 pixels, as blend_scalar in 16-bit lanes (every intermediate stays below 2^16);
// returns how many pixels it wrote.
FAULTLINE_TARGET("avx2")
int blend_avx2(const std::uint8_t* src, const std::uint8_t* layer, const std::uint8_t* rot,
               bool rot_reversed, std::uint8_t* dst, int cols, const BlendFixed& f) {
  const Shuffles& m = shuffles();
  const __m256i grey0 = set16(BlendFixed::kGrey0), grey1 = set16(BlendFixed::kGrey1);
  const __m256i grey2 = set16(BlendFixed::kGrey2), offset = set16(BlendFixed::kBrightOffset);
  const __m256i bv = set16(f.b14), omb = set16(f.one_minus_b15);
  int x = 0;
  for (; x + 16 <= cols; x += 16) {
    __m128i plane[3];
    load_planes(m, src, x, plane);
    __m256i c8[3];
    for (int k = 0; k < 3; ++k) c8[k] = _mm256_slli_epi16(_mm256_cvtepu8_epi16(plane[k]), 8);
    const __m256i bright = _mm256_add_epi16(
        _mm256_add_epi16(_mm256_mulhi_epu16(c8[0], grey0), _mm256_mulhi_epu16(c8[1], grey1)),
        _mm256_add_epi16(_mm256_mulhi_epu16(c8[2], grey2), offset));
    const __m128i l = _mm_loadu_si128(reinterpret_cast<const __m128i*>(layer + x));
    const __m128i r = load_rotated(rot, rot_reversed, cols, x);
    const __m256i snow =
        _mm256_slli_epi16(_mm256_add_epi16(_mm256_cvtepu8_epi16(l), _mm256_cvtepu8_epi16(r)), 6);
    __m128i res[3];
    for (int k = 0; k < 3; ++k) {
      const __m256i mx = _mm256_max_epu16(_mm256_srli_epi16(c8[k], 2), bright);
      const __m256i v =
          _mm256_add_epi16(_mm256_add_epi16(_mm256_mulhi_epu16(c8[k], bv),
                                            _mm256_mulhi_epu16(_mm256_slli_epi16(mx, 1), omb)),
                           snow);
      const __m256i o = _mm256_srli_epi16(v, 6);
      res[k] = _mm_packus_epi16(_mm256_castsi256_si128(o), _mm256_extracti128_si256(o, 1));
    }
    merge_planes(m, res, dst, x);
  }
  return x;
}

// Four float32 values (the low or high half of an 8-lane vector) widened, plus the two snow terms,
// to bytes. _mm_srli_si128 by 0, 4, 8 or 12 bytes. The intrinsic needs a compile-time constant; gcc
// folds the loop counters below into one, clang 14 refuses to (with constant arguments the switch
// folds away).
FAULTLINE_TARGET("avx2") inline __m128i bytes_right(__m128i v, int bytes) {
  switch (bytes) {
    case 0:
      return v;
    case 4:
      return _mm_srli_si128(v, 4);
    case 8:
      return _mm_srli_si128(v, 8);
    default:
      return _mm_srli_si128(v, 12);
  }
}

FAULTLINE_TARGET("avx2,fma")
inline __m128i finish4(__m128 whitened, __m256d snow, __m256d snow_rot) {
  __m256d v = _mm256_add_pd(_mm256_add_pd(_mm256_cvtps_pd(whitened), snow), snow_rot);
  v = _mm256_min_pd(_mm256_max_pd(v, _mm256_setzero_pd()), _mm256_set1_pd(1.0));
  return _mm256_cvttpd_epi32(_mm256_mul_pd(v, _mm256_set1_pd(255.0)));
}

// Whole blocks of 16 pixels; returns how many pixels it wrote.
FAULTLINE_TARGET("avx2,fma")
int blend_exact_avx2(const std::uint8_t* src, const std::uint8_t* layer, const std::uint8_t* rot,
                     bool rot_reversed, std::uint8_t* dst, int cols, float b, float one_minus_b) {
  const Shuffles& m = shuffles();
  const __m256 bv = _mm256_set1_ps(b), omb = _mm256_set1_ps(one_minus_b),
               k255f = _mm256_set1_ps(255.0f);
  const __m256 w0 = _mm256_set1_ps(0.299f), w1 = _mm256_set1_ps(0.587f),
               w2 = _mm256_set1_ps(0.114f);
  const __m256 k15 = _mm256_set1_ps(1.5f), k05 = _mm256_set1_ps(0.5f);
  const __m256d k255 = _mm256_set1_pd(255.0);
  int x = 0;
  for (; x + 16 <= cols; x += 16) {
    __m128i plane[3];
    load_planes(m, src, x, plane);
    const __m128i l = _mm_loadu_si128(reinterpret_cast<const __m128i*>(layer + x));
    const __m128i r = load_rotated(rot, rot_reversed, cols, x);
    __m256i out[3][2];
    for (int h = 0; h < 2; ++h) {
      __m256 c[3];
      for (int k = 0; k < 3; ++k) {
        c[k] = _mm256_div_ps(_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes_right(plane[k], 8 * h))),
                             k255f);
      }
      const __m256 grey =
          _mm256_fmadd_ps(c[2], w2, _mm256_fmadd_ps(c[1], w1, _mm256_mul_ps(c[0], w0)));
      const __m256 bright = _mm256_add_ps(_mm256_mul_ps(grey, k15), k05);
      __m256d snow[2], snow_rot[2];
      for (int q = 0; q < 2; ++q) {
        const int shift = 8 * h + 4 * q;
        const __m128i l4 = _mm_cvtepu8_epi32(bytes_right(l, shift));
        const __m128i r4 = _mm_cvtepu8_epi32(bytes_right(r, shift));
        snow[q] = _mm256_div_pd(_mm256_cvtepi32_pd(l4), k255);
        snow_rot[q] = _mm256_div_pd(_mm256_cvtepi32_pd(r4), k255);
      }
      for (int k = 0; k < 3; ++k) {
        const __m256 wf =
            _mm256_add_ps(_mm256_mul_ps(bv, c[k]), _mm256_mul_ps(omb, _mm256_max_ps(c[k], bright)));
        const __m128i lo = finish4(_mm256_castps256_ps128(wf), snow[0], snow_rot[0]);
        const __m128i hi = finish4(_mm256_extractf128_ps(wf, 1), snow[1], snow_rot[1]);
        out[k][h] = _mm256_set_m128i(hi, lo);
      }
    }
    store_planes(m, out, dst, x);
  }
  return x;
}

#endif  // FAULTLINE_X86_SIMD

// The exact blend per pixel. The FMA clone turns std::fma into one instruction (same result as the
// library call); contraction stays off, so nothing else is fused.
FAULTLINE_CLONES("fma")
void blend_exact_scalar(const std::uint8_t* src, const std::uint8_t* l, const std::uint8_t* rot,
                        bool rot_reversed, std::uint8_t* dst, int x0, int cols, float b,
                        float one_minus_b) {
  for (int x = x0; x < cols; ++x) {
    const float c0 = static_cast<float>(src[3 * x]) / 255.0f;
    const float c1 = static_cast<float>(src[3 * x + 1]) / 255.0f;
    const float c2 = static_cast<float>(src[3 * x + 2]) / 255.0f;
    // OpenCV's AVX2 RGB2GRAY: fma(ch2, 0.114, fma(ch1, 0.587, ch0 * 0.299)) in float32.
    const float grey = std::fma(c2, 0.114f, std::fma(c1, 0.587f, c0 * 0.299f));
    const float bright = grey * 1.5f + 0.5f;
    const double snow = l[x] / 255.0;
    const double snow_rot = (rot_reversed ? rot[cols - 1 - x] : rot[x]) / 255.0;
    const float ch[3] = {c0, c1, c2};
    for (int k = 0; k < 3; ++k) {
      const float whitened = b * ch[k] + one_minus_b * std::max(ch[k], bright);
      const double v = (static_cast<double>(whitened) + snow) + snow_rot;
      dst[3 * x + k] = static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0);
    }
  }
}

}  // namespace

void blend_fast_row(const std::uint8_t* src, const std::uint8_t* layer, const std::uint8_t* rot,
                    bool rot_reversed, std::uint8_t* dst, int cols, float b, float one_minus_b,
                    bool allow_simd) {
  const BlendFixed f(b, one_minus_b);
  int x = 0;
#if FAULTLINE_X86_SIMD
  if (use_avx2(allow_simd)) x = blend_avx2(src, layer, rot, rot_reversed, dst, cols, f);
#else
  (void)allow_simd;
#endif
  blend_scalar(src, layer, rot, rot_reversed, dst, x, cols, f);
}

void blend_exact_row(const std::uint8_t* src, const std::uint8_t* layer, const std::uint8_t* rot,
                     bool rot_reversed, std::uint8_t* dst, int cols, float b, float one_minus_b,
                     bool allow_simd) {
  int x = 0;
#if FAULTLINE_X86_SIMD
  if (allow_simd && common::cpu_has_avx2_fma())
    x = blend_exact_avx2(src, layer, rot, rot_reversed, dst, cols, b, one_minus_b);
#else
  (void)allow_simd;
#endif
  blend_exact_scalar(src, layer, rot, rot_reversed, dst, x, cols, b, one_minus_b);
}

}  // namespace faultline::corruption::snow_kernels
