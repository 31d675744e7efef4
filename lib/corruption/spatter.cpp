// Spatter: liquid field, then the water (OpenCV edge pipeline) or mud (blurred mask) blend.
#include "corruption/spatter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/simd.hpp"
#include "corruption/ndimage.hpp"
#include "corruption/spatter_mud.hpp"
#include "corruption/spatter_water.hpp"

namespace faultline::corruption {

namespace {

// The water tint per pixel (float32, before the colour): the emboss-filtered edge distance times
// the liquid.
cv::Mat water_strength(const cv::Mat& liquid, float& max_value) {
  cv::Mat liquid8(liquid.size(), CV_8U);
  for (int y = 0; y < liquid.rows; ++y) {
    const double* s = liquid.ptr<double>(y);
    unsigned char* o = liquid8.ptr<unsigned char>(y);
    for (int x = 0; x < liquid.cols; ++x) o[x] = nd::to_u8_wrap(s[x] * 255);  // astype(np.uint8)
  }
  cv::Mat edges, dist;
  cv::Canny(liquid8, edges, 50, 150);
  edges = 255 - edges;
  cv::distanceTransform(edges, dist, cv::DIST_L2, 5);
  cv::threshold(dist, dist, 20, 20, cv::THRESH_TRUNC);
  cv::blur(dist, dist, cv::Size(3, 3));
  cv::Mat dist8(dist.size(), CV_8U);
  for (int y = 0; y < dist.rows; ++y) {
    const float* s = dist.ptr<float>(y);
    unsigned char* o = dist8.ptr<unsigned char>(y);
    for (int x = 0; x < dist.cols; ++x) o[x] = nd::to_u8_wrap(s[x]);
  }
  cv::equalizeHist(dist8, dist8);
  const cv::Mat_<int> emboss = (cv::Mat_<int>(3, 3) << -2, -1, 0, -1, 1, 1, 0, 1, 2);
  cv::filter2D(dist8, dist8, CV_8U, emboss);
  cv::blur(dist8, dist8, cv::Size(3, 3));
  cv::Mat m(liquid.size(), CV_32F);
  max_value = 0.f;
  for (int y = 0; y < m.rows; ++y) {
    const unsigned char* l = liquid8.ptr<unsigned char>(y);
    const unsigned char* d = dist8.ptr<unsigned char>(y);
    float* o = m.ptr<float>(y);
    for (int x = 0; x < m.cols; ++x) {
      o[x] = static_cast<float>(l[x]) * static_cast<float>(d[x]);
      max_value = std::max(max_value, o[x]);
    }
  }
  return m;
}

cv::Mat water_blend(const cv::Mat& bgr, const cv::Mat& liquid, const SpatterParams& p) {
  float max_value = 0.f;
  const cv::Mat m = water_strength(liquid, max_value);
  if (max_value == 0.f) return bgr.clone();  // no liquid: see the header
  const float intensity = static_cast<float>(p.intensity);
  const float colour[3] = {static_cast<float>(175 / 255.), static_cast<float>(238 / 255.),
                           static_cast<float>(238 / 255.)};
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    const unsigned char* s = bgr.ptr<unsigned char>(y);
    const float* mm = m.ptr<float>(y);
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      const float k = (mm[x] / max_value) * intensity;
      for (int c = 0; c < 3; ++c) {
        const float v = static_cast<float>(s[3 * x + c]) / 255.f + k * colour[c];
        o[3 * x + c] = static_cast<unsigned char>(std::min(std::max(v, 0.f), 1.f) * 255.f);
      }
    }
  }
  return out;
}

cv::Mat mud_blend(const cv::Mat& bgr, const cv::Mat& liquid, const SpatterParams& p,
                  bool exact_blur) {
  cv::Mat mask(liquid.size(), CV_32F);
  for (int y = 0; y < liquid.rows; ++y) {
    const double* s = liquid.ptr<double>(y);
    float* o = mask.ptr<float>(y);
    for (int x = 0; x < liquid.cols; ++x) o[x] = s[x] > p.threshold ? 1.f : 0.f;
  }
  if (exact_blur) {
    nd::gaussian_filter(mask, p.intensity, p.intensity, nd::Extend::Nearest);
  } else {
    cv::GaussianBlur(mask, mask, cv::Size(), p.intensity, p.intensity, cv::BORDER_REPLICATE);
  }
  const double colour[3] = {63 / 255., 42 / 255., 20 / 255.};
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    const unsigned char* s = bgr.ptr<unsigned char>(y);
    const float* mm = mask.ptr<float>(y);
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      const float m = mm[x] < 0.8f ? 0.f : mm[x];
      for (int c = 0; c < 3; ++c) {
        const float kept = (static_cast<float>(s[3 * x + c]) / 255.f) * (1.f - m);
        const double v = static_cast<double>(kept) + colour[c] * static_cast<double>(m);
        o[3 * x + c] = static_cast<unsigned char>(std::min(std::max(v, 0.0), 1.0) * 255.0);
      }
    }
  }
  return out;
}

// fast mode's water: liquid8 and the tint's strength from spatter_water.cpp, the blend here.

// The water's blend: v = min(v + trunc(k colour), 255), k = liquid8 * strength * scale (<= the
// intensity, so each tint is < 256). (numpy mode truncates v + k colour as a whole: it differs
// where that float sum rounds up to the next integer, by one level.)
constexpr float kWaterColour[3] = {175.f, 238.f, 238.f};

void water_pixel(std::uint8_t* out, const std::uint8_t* in, int product, float scale) {
  const float k = static_cast<float>(product) * scale;
  for (int c = 0; c < 3; ++c) {
    const int tint = std::min(static_cast<int>(k * kWaterColour[c]), 255);
    out[c] = static_cast<std::uint8_t>(std::min(in[c] + tint, 255));
  }
}

#if FAULTLINE_X86_SIMD
// The byte shuffles that spread 16 per-pixel tints over the 48 bytes of 16 BGR pixels: chunk c,
// byte j is pixel (16 c + j) / 3's channel (16 c + j) % 3, taken from the channel-0 tints (first)
// or the channel-1/2 tints (second, the colour's two 238s); -128 leaves a zero.
struct TintShuffles {
  alignas(16) std::int8_t first[3][16];
  alignas(16) std::int8_t second[3][16];
  TintShuffles() {
    for (int i = 0; i < 48; ++i) {
      const auto pixel = static_cast<std::int8_t>(i / 3);
      first[i / 16][i % 16] = i % 3 == 0 ? pixel : std::int8_t{-128};
      second[i / 16][i % 16] = i % 3 == 0 ? std::int8_t{-128} : pixel;
    }
  }
};

FAULTLINE_TARGET("avx2")
std::size_t water_avx2(std::uint8_t* out, const std::uint8_t* in, const std::uint8_t* liquid,
                       const std::uint8_t* strength, float scale, std::size_t pixels) {
  static const TintShuffles shuffles;
  const __m256 scalev = _mm256_set1_ps(scale);
  const __m256 colour0 = _mm256_set1_ps(kWaterColour[0]), colour1 = _mm256_set1_ps(kWaterColour[1]);
  auto tints = [&](__m256 klo, __m256 khi, __m256 colour) FAULTLINE_TARGET_INLINE("avx2") {
    const __m256i lo = _mm256_cvttps_epi32(_mm256_mul_ps(klo, colour));
    const __m256i hi = _mm256_cvttps_epi32(_mm256_mul_ps(khi, colour));
    const __m256i words = _mm256_permute4x64_epi64(_mm256_packus_epi32(lo, hi), 0xD8);
    return _mm_packus_epi16(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
  };
  std::size_t x = 0;
  for (; x + 16 <= pixels; x += 16) {
    const __m256i l =
        _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(liquid + x)));
    const __m256i s =
        _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(strength + x)));
    const __m256i product = _mm256_mullo_epi16(l, s);  // <= 255^2: read as unsigned below
    const __m256 klo = _mm256_mul_ps(
        _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm256_castsi256_si128(product))), scalev);
    const __m256 khi = _mm256_mul_ps(
        _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm256_extracti128_si256(product, 1))), scalev);
    const __m128i t0 = tints(klo, khi, colour0), t1 = tints(klo, khi, colour1);
    for (int c = 0; c < 3; ++c) {
      const __m128i tint = _mm_or_si128(
          _mm_shuffle_epi8(t0, _mm_load_si128(reinterpret_cast<const __m128i*>(shuffles.first[c]))),
          _mm_shuffle_epi8(t1,
                           _mm_load_si128(reinterpret_cast<const __m128i*>(shuffles.second[c]))));
      const std::size_t at = 3 * x + 16 * static_cast<std::size_t>(c);
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + at));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + at), _mm_adds_epu8(v, tint));
    }
  }
  return x;
}
#endif

void water_row(std::uint8_t* out, const std::uint8_t* in, const std::uint8_t* liquid,
               const std::uint8_t* strength, float scale, std::size_t pixels, bool simd) {
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (simd) x = water_avx2(out, in, liquid, strength, scale, pixels);
#else
  (void)simd;
#endif
  for (; x < pixels; ++x) water_pixel(out + 3 * x, in + 3 * x, liquid[x] * strength[x], scale);
}

cv::Mat water_blend_fast(const cv::Mat& bgr, const SpatterParams& p, rng::FastRng& rng) {
  thread_local WaterScratch scratch;
  water_liquid8(bgr.size(), p, rng, scratch);
  const int max_value = water_strength_fast(scratch);
  const cv::Mat& liquid8 = scratch.liquid8;
  const cv::Mat& dist8 = scratch.strength;
  const auto n = static_cast<std::size_t>(liquid8.cols);
  if (max_value == 0) return bgr.clone();  // no liquid: see the header
  const auto scale = static_cast<float>(p.intensity / max_value);
  cv::Mat out(bgr.size(), CV_8UC3);
  const bool simd = common::cpu_has_avx2();
  for (int y = 0; y < bgr.rows; ++y) {
    water_row(out.ptr<std::uint8_t>(y), bgr.ptr<std::uint8_t>(y), liquid8.ptr<std::uint8_t>(y),
              dist8.ptr<std::uint8_t>(y), scale, n, simd);
  }
  return out;
}

}  // namespace

SpatterParams spatter_params(int severity) {
  static constexpr SpatterParams kParams[] = {{0.65, 0.3, 4, 0.69, 0.6, false},
                                              {0.65, 0.3, 3, 0.68, 0.6, false},
                                              {0.65, 0.3, 2, 0.68, 0.5, false},
                                              {0.65, 0.3, 1, 0.65, 1.5, true},
                                              {0.67, 0.4, 1, 0.65, 1.5, true}};
  return kParams[severity - 1];
}

cv::Mat spatter_apply(const cv::Mat& bgr, const cv::Mat& liquid, int severity, bool exact_blur) {
  const SpatterParams p = spatter_params(severity);
  return p.mud ? mud_blend(bgr, liquid, p, exact_blur) : water_blend(bgr, liquid, p);
}

cv::Mat spatter_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const SpatterParams p = spatter_params(severity);
  cv::Mat liquid(bgr.size(), CV_64F);
  for (int y = 0; y < bgr.rows; ++y) {
    double* o = liquid.ptr<double>(y);
    for (int x = 0; x < bgr.cols; ++x) o[x] = rng.normal(p.loc, p.scale);
  }
  nd::gaussian_filter(liquid, p.sigma, p.sigma, nd::Extend::Nearest);
  liquid.setTo(0.0, liquid < p.threshold);
  return spatter_apply(bgr, liquid, severity, true);
}

cv::Mat spatter_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const SpatterParams p = spatter_params(severity);
  // The field smoothed in float32 with the kernel to 3 sigma (OpenCV's default for float goes to
  // 4; 0.3 % of the weight). (Drawing the water's field at half resolution and upsampling it was
  // tried: it smooths away the weak edges Canny finds inside the liquid, and the tint's histogram
  // moves twice as far from numpy mode's as another seed's does.)
  if (!p.mud) return water_blend_fast(bgr, p, rng);
  // Mud (sigma 1: too few draws per value for other draws than normals, e.g. the water's
  // triangular ones): Box-Muller normals, everything streamed by rows (spatter_mud.hpp).
  return mud_blend_fast(bgr, p, rng);
}

}  // namespace faultline::corruption
