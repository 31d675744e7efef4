// contrast and saturate: per-channel tables and a per-pixel mirror of skimage's HSV float path.
#include "corruption/digital.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/simd.hpp"
#include "corruption/skimage_hsv.hpp"

namespace faultline::corruption {
namespace {

std::size_t sev_index(int severity) {
  return static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1);
}

using skimage::to_u8;

cv::Mat continuous(const cv::Mat& m) { return m.isContinuous() ? m : m.clone(); }

// One pixel through rgb2hsv, S = clip(S * a + b, 0, 1), hsv2rgb (skimage 0.19, channels in stored
// order).
void saturate_pixel(const std::uint8_t* in, std::uint8_t* out, double a, double b) {
  const skimage::Hsv hsv = skimage::rgb_to_hsv(in);
  skimage::hsv_to_rgb_u8(hsv.h, std::min(std::max(hsv.s * a + b, 0.0), 1.0), hsv.v, out);
}

}  // namespace

double contrast_factor(int severity) {
  static constexpr double kC[] = {0.4, .3, .2, .1, .05};
  return kC[sev_index(severity)];
}

cv::Mat contrast(const cv::Mat& bgr, int severity) {
  const double c = contrast_factor(severity);
  const cv::Mat in = continuous(bgr);
  double x_of[256];
  for (int v = 0; v < 256; ++v) x_of[v] = v / 255.0;
  // numpy reduces axes (0, 1) with the channel axis innermost: one running float64 sum per channel,
  // in pixel order.
  double sum[3] = {0.0, 0.0, 0.0};
  const std::size_t pixels = in.total();
  const std::uint8_t* src = in.data;
  for (std::size_t i = 0; i < pixels; ++i) {
    sum[0] += x_of[src[3 * i]];
    sum[1] += x_of[src[3 * i + 1]];
    sum[2] += x_of[src[3 * i + 2]];
  }
  std::uint8_t lut[3][256];
  for (int ch = 0; ch < 3; ++ch) {
    const double mean = sum[ch] / static_cast<double>(pixels);
    for (int v = 0; v < 256; ++v) lut[ch][v] = to_u8((x_of[v] - mean) * c + mean);
  }
  cv::Mat out(in.size(), CV_8UC3);
  std::uint8_t* dst = out.data;
  for (std::size_t i = 0; i < pixels; ++i) {
    dst[3 * i] = lut[0][src[3 * i]];
    dst[3 * i + 1] = lut[1][src[3 * i + 1]];
    dst[3 * i + 2] = lut[2][src[3 * i + 2]];
  }
  return out;
}

namespace {
constexpr double kSatA[] = {0.3, 0.1, 2, 5, 20};
constexpr double kSatB[] = {0, 0, 0, 0.1, 0.2};
}  // namespace

SaturateParams saturate_params(int severity) {
  return {kSatA[sev_index(severity)], kSatB[sev_index(severity)]};
}

namespace {

// One row of saturate_fast on planar float copies of its channels (p0, p1, p2; pixels from..n-1,
// overwritten with the results): the portable path and the AVX2 path's tail. The AVX2 path runs the
// same operations in the same order on 8 pixels at a step, so they give the same bytes.
void saturate_planar(float* p0, float* p1, float* p2, std::size_t from, std::size_t n, float a,
                     float b) {
  for (std::size_t i = from; i < n; ++i) {
    const float c0 = p0[i], c1 = p1[i], c2 = p2[i];
    const float v = std::max(std::max(c0, c1), c2), lo = std::min(std::min(c0, c1), c2);
    const float s = v > 0.0f ? (v - lo) / v : 0.0f;
    const float s2 = std::min(std::max(s * a + b, 0.0f), 1.0f);
    // Every channel moves towards or away from V by the same factor: c' = v - (v - c) * s2 / s. A
    // grey pixel has hue 0 (channel 0) in skimage, so an offset b tints it: (v, v (1 - s2), v (1 -
    // s2)).
    const float k = v > lo ? s2 * v / (v - lo) : 0.0f;
    const float grey_tail = v > lo ? 0.0f : v * s2;
    p0[i] = std::min(std::max(v - (v - c0) * k, 0.0f), 255.0f);
    p1[i] = std::min(std::max(v - (v - c1) * k - grey_tail, 0.0f), 255.0f);
    p2[i] = std::min(std::max(v - (v - c2) * k - grey_tail, 0.0f), 255.0f);
  }
}

#if FAULTLINE_X86_SIMD
// Eight pixels' channels through saturate_planar's arithmetic. The divisions run on every lane, so
// their divisors are kept >= 1: the values are integers, so max(x, 1) = x wherever a quotient is
// used, and v = 0 means lo = 0, s = 0. max/min of non-NaN values equal std::max/min's; no FMA
// (products rounded before the adds, as there).
struct Saturate8 {
  __m256 c[3];
};

FAULTLINE_TARGET_INLINE("avx2")
inline Saturate8 saturate8(const Saturate8& in, __m256 va, __m256 vb) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), top = _mm256_set1_ps(255.0f);
  const __m256 c0 = in.c[0], c1 = in.c[1], c2 = in.c[2];
  const __m256 v = _mm256_max_ps(_mm256_max_ps(c0, c1), c2),
               lo = _mm256_min_ps(_mm256_min_ps(c0, c1), c2);
  const __m256 span = _mm256_sub_ps(v, lo);
  const __m256 s = _mm256_div_ps(span, _mm256_max_ps(v, one));
  const __m256 s2 =
      _mm256_min_ps(_mm256_max_ps(_mm256_add_ps(_mm256_mul_ps(s, va), vb), zero), one);
  const __m256 coloured = _mm256_cmp_ps(v, lo, _CMP_GT_OQ);
  const __m256 k =
      _mm256_and_ps(coloured, _mm256_div_ps(_mm256_mul_ps(s2, v), _mm256_max_ps(span, one)));
  const __m256 grey_tail = _mm256_andnot_ps(coloured, _mm256_mul_ps(v, s2));
  const auto channel = [&](__m256 c, __m256 tail) FAULTLINE_TARGET_INLINE("avx2") {
    const __m256 o = _mm256_sub_ps(_mm256_sub_ps(v, _mm256_mul_ps(_mm256_sub_ps(v, c), k)), tail);
    return _mm256_min_ps(_mm256_max_ps(o, zero), top);
  };
  return {{channel(c0, zero), channel(c1, grey_tail), channel(c2, grey_tail)}};
}

// The byte shuffles between 8 interleaved pixels (24 bytes: `first` = bytes 0-15, `second` = bytes
// 8-23) and their channels (8 bytes each); -128 leaves a zero.
struct PixelShuffles {
  alignas(16) std::int8_t from_first[3][16], from_second[3][16];  // channel c's bytes
  alignas(16) std::int8_t to_first[2][16], to_last[2][16];        // from [c0 | c1] and [c2 | -]
  PixelShuffles() {
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < 16; ++i) {
        const int at = 3 * i + c;  // pixel i's channel c, for i < 8
        from_first[c][i] = static_cast<std::int8_t>(i < 8 && at < 16 ? at : -128);
        from_second[c][i] = static_cast<std::int8_t>(i < 8 && at >= 16 ? at - 8 : -128);
      }
    }
    for (int j = 0; j < 16; ++j) {
      for (int half = 0; half < 2; ++half) {
        const int at = 16 * half + j;  // output byte: pixel at / 3, channel at % 3
        const int pixel = at / 3, c = at % 3;
        const bool in_range = at < 24;
        to_first[half][j] = static_cast<std::int8_t>(in_range && c < 2 ? 8 * c + pixel : -128);
        to_last[half][j] = static_cast<std::int8_t>(in_range && c == 2 ? pixel : -128);
      }
    }
  }
};

// Returns how many pixels it did (whole steps of 8), reading and writing the interleaved bytes.
FAULTLINE_TARGET("avx2")
std::size_t saturate_bytes_avx2(std::uint8_t* dst, const std::uint8_t* src, std::size_t n, float a,
                                float b) {
  static const PixelShuffles sh;
  const __m256 va = _mm256_set1_ps(a), vb = _mm256_set1_ps(b);
  auto mask = [](const std::int8_t* m) FAULTLINE_TARGET_INLINE("avx2") {
    return _mm_load_si128(reinterpret_cast<const __m128i*>(m));
  };
  std::size_t i = 0;
  // The last step reads 24 bytes: stop where they end inside the row.
  for (; i + 8 <= n; i += 8) {
    const __m128i first = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + 3 * i));
    const __m128i second = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + 3 * i + 8));
    Saturate8 px;
    for (int c = 0; c < 3; ++c) {
      const __m128i bytes = _mm_or_si128(_mm_shuffle_epi8(first, mask(sh.from_first[c])),
                                         _mm_shuffle_epi8(second, mask(sh.from_second[c])));
      px.c[c] = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes));
    }
    const Saturate8 out = saturate8(px, va, vb);
    __m128i ch[3];
    for (int c = 0; c < 3; ++c) {  // 0..255: truncation as the portable loop's
      const __m256i v = _mm256_cvttps_epi32(out.c[c]);
      const __m128i words =
          _mm_packus_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
      ch[c] = _mm_packus_epi16(words, words);
    }
    const __m128i c01 = _mm_unpacklo_epi64(ch[0], ch[1]);
    const __m128i low = _mm_or_si128(_mm_shuffle_epi8(c01, mask(sh.to_first[0])),
                                     _mm_shuffle_epi8(ch[2], mask(sh.to_last[0])));
    const __m128i high = _mm_or_si128(_mm_shuffle_epi8(c01, mask(sh.to_first[1])),
                                      _mm_shuffle_epi8(ch[2], mask(sh.to_last[1])));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + 3 * i), low);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(dst + 3 * i + 16), high);
  }
  return i;
}
#endif

}  // namespace

cv::Mat saturate_fast(const cv::Mat& bgr, int severity) {
  const float a = static_cast<float>(kSatA[sev_index(severity)]),
              b = static_cast<float>(kSatB[sev_index(severity)]);
  cv::Mat out(bgr.size(), CV_8UC3);
  const std::size_t cols = static_cast<std::size_t>(bgr.cols);
  std::vector<float> planes(3 * cols);
  float *p0 = planes.data(), *p1 = p0 + cols, *p2 = p1 + cols;
  for (int y = 0; y < bgr.rows; ++y) {
    const std::uint8_t* src = bgr.ptr<std::uint8_t>(y);
    std::uint8_t* dst = out.ptr<std::uint8_t>(y);
    std::size_t done = 0;
#if FAULTLINE_X86_SIMD
    if (common::cpu_has_avx2()) done = saturate_bytes_avx2(dst, src, cols, a, b);
#endif
    for (std::size_t i = done; i < cols; ++i) {
      p0[i] = src[3 * i], p1[i] = src[3 * i + 1], p2[i] = src[3 * i + 2];
    }
    saturate_planar(p0, p1, p2, done, cols, a, b);
    for (std::size_t i = done; i < cols; ++i) {  // the values are in 0..255: truncation
      dst[3 * i] = static_cast<std::uint8_t>(p0[i]);
      dst[3 * i + 1] = static_cast<std::uint8_t>(p1[i]);
      dst[3 * i + 2] = static_cast<std::uint8_t>(p2[i]);
    }
  }
  return out;
}

cv::Mat saturate(const cv::Mat& bgr, int severity) {
  const double a = kSatA[sev_index(severity)], b = kSatB[sev_index(severity)];
  const cv::Mat in = continuous(bgr);
  cv::Mat out(in.size(), CV_8UC3);
  const std::size_t n = in.total();
  for (std::size_t i = 0; i < n; ++i) saturate_pixel(in.data + 3 * i, out.data + 3 * i, a, b);
  return out;
}

}  // namespace faultline::corruption
