// Glass Blur: blur, local pixel copies in the reference's order, blur (fast mode: fixed-point
// blurs).
#include "corruption/glass_blur.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "common/simd.hpp"
#include "corruption/fixed_point_blur.hpp"
#include "corruption/ndimage.hpp"
#include "rng/lane_rng.hpp"
#include "rng/lane_rng_avx2.hpp"

namespace faultline::corruption {

namespace {

// The pixel walk; draw() returns one offset in [-d, d).
template <typename Draw>
void shuffle_pixels(cv::Mat& img, const GlassParams& p, Draw&& draw) {
  const int d = p.delta;
  for (int it = 0; it < p.iterations; ++it) {
    for (int h = img.rows - d; h > d; --h) {
      for (int w = img.cols - d; w > d; --w) {
        const int dx = draw();
        const int dy = draw();
        const unsigned char* src = img.ptr<unsigned char>(h + dy) + 3 * (w + dx);
        unsigned char* dst = img.ptr<unsigned char>(h) + 3 * w;
        dst[0] = src[0], dst[1] = src[1], dst[2] = src[2];
      }
    }
  }
}

// fast mode's blur: numpy mode's kernel in the fixed-point blur (exact integer sums, truncated
// like the reference's float64 ones). Where the reference's float64 sum of a flat neighbourhood
// lands a hair below its integer, it truncates one level down, for some levels and not others: a
// sum that lands on an integer k (every flat neighbourhood's does) takes the reference's flat
// result for k (`flat`).
struct FastBlur {
  FixedPointKernel kernel;
  std::array<std::uint8_t, 256> flat{};  // the reference's output on a flat neighbourhood of v
};

FastBlur fast_blur(double sigma) {
  const std::vector<double> w = nd::gaussian_kernel(sigma, nd::gaussian_radius(sigma, 4.0));
  FastBlur b;
  b.kernel = fixed_point_kernel(w);
  const int r = b.kernel.radius;
  for (int v = 0; v < 256; ++v) {
    // nd::gaussian_blur_u8's operations on equal taps: axis 0, then axis 1, then the store.
    const double c = v / 255.0;
    double mid = c * w[0];
    for (int k = r; k >= 1; --k) mid += (c + c) * w[static_cast<std::size_t>(k)];
    double acc = mid * w[0];
    for (int k = r; k >= 1; --k) acc += (mid + mid) * w[static_cast<std::size_t>(k)];
    b.flat[static_cast<std::size_t>(v)] =
        static_cast<std::uint8_t>(std::min(std::max(acc, 0.0), 1.0) * 255.0);
  }
  return b;
}

// fast mode's offsets: one 32-bit LaneRng value per pixel, dx from its low 16 bits and dy from its
// high 16, each scaled to [-d, d) by multiply and shift (uniform for d = 1, 2, 4; for d = 3 four of
// the six values are 1 / 10922 more likely than the other two, far below anything the output
// shows), turned into the byte offset dy * row_step + 3 dx (detail::glass_row_offsets).
struct OffsetMap {
  std::int32_t span, delta, row_step;
  std::int32_t operator()(std::uint32_t v) const {
    const auto dx =
        static_cast<std::int32_t>(((v & 0xFFFFu) * static_cast<std::uint32_t>(span)) >> 16);
    const auto dy = static_cast<std::int32_t>(((v >> 16) * static_cast<std::uint32_t>(span)) >> 16);
    return (dy - delta) * row_step + 3 * (dx - delta);
  }
};

#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET_INLINE("avx2") inline __m256i map_offsets(__m256i v, const OffsetMap& m) {
  const __m256i low = _mm256_set1_epi32(0xFFFF), span = _mm256_set1_epi32(m.span);
  const __m256i delta = _mm256_set1_epi32(m.delta);
  const __m256i dx = _mm256_srli_epi32(_mm256_mullo_epi32(_mm256_and_si256(v, low), span), 16);
  const __m256i dy = _mm256_srli_epi32(_mm256_mullo_epi32(_mm256_srli_epi32(v, 16), span), 16);
  const __m256i x3 = _mm256_mullo_epi32(_mm256_sub_epi32(dx, delta), _mm256_set1_epi32(3));
  const __m256i y = _mm256_mullo_epi32(_mm256_sub_epi32(dy, delta), _mm256_set1_epi32(m.row_step));
  return _mm256_add_epi32(y, x3);
}

FAULTLINE_TARGET("avx2")
void row_offsets_avx2(std::int32_t* out, std::size_t steps, rng::LaneRng& lanes,
                      const OffsetMap& m) {
  rng::avx2::Xoshiro4 a = rng::avx2::load_half(lanes, 0), b = rng::avx2::load_half(lanes, 1);
  for (std::size_t s = 0; s < steps; ++s, out += 16) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), map_offsets(rng::avx2::step(a), m));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 8), map_offsets(rng::avx2::step(b), m));
  }
  rng::avx2::store_half(a, lanes, 0);
  rng::avx2::store_half(b, lanes, 1);
}
#endif

// shuffle_pixels with glass_row_offsets' draws, a row's offsets drawn before its serial copy loop
// (a copy may read a pixel the walk wrote).
void walk_fast(cv::Mat& img, const GlassParams& p, rng::FastRng& rng) {
  const int d = p.delta;
  if (img.cols - 2 * d <= 0) return;
  const auto count = static_cast<std::size_t>(img.cols - 2 * d);
  std::vector<std::int32_t> offset((count + 15) / 16 * 16);
  const auto row_step = static_cast<std::int32_t>(img.step[0]);
  rng::LaneRng lanes(rng);
  for (int it = 0; it < p.iterations; ++it) {
    for (int h = img.rows - d; h > d; --h) {
      detail::glass_row_offsets(offset.data(), count, lanes, d, row_step);
      unsigned char* px = img.ptr<unsigned char>(h) + 3 * (img.cols - d);  // w = cols - d first
      for (std::size_t k = 0; k < count; ++k, px -= 3) {
        // Two loads and two stores where three of each did it (src is px or a whole pixel away).
        const unsigned char* src = px + offset[k];
        std::uint16_t first;
        std::memcpy(&first, src, 2);
        const unsigned char last = src[2];
        std::memcpy(px, &first, 2);
        px[2] = last;
      }
    }
  }
}

}  // namespace

namespace detail {

void glass_row_offsets(std::int32_t* out, std::size_t count, rng::LaneRng& lanes, int delta,
                       std::int32_t row_step, bool allow_simd) {
  const OffsetMap m{2 * delta, delta, row_step};
  const std::size_t steps = (count + 15) / 16;
#if FAULTLINE_X86_SIMD
  if (allow_simd && common::cpu_has_avx2()) return row_offsets_avx2(out, steps, lanes, m);
#else
  (void)allow_simd;
#endif
  std::uint32_t v[rng::LaneRng::kValuesPerStep];
  for (std::size_t s = 0; s < steps; ++s, out += 16) {
    lanes.next_values(v);
    for (std::size_t i = 0; i < 16; ++i) out[i] = m(v[i]);
  }
}

}  // namespace detail

GlassParams glass_params(int severity) {
  static constexpr GlassParams kParams[] = {
      {0.7, 1, 2}, {0.9, 2, 1}, {1, 2, 3}, {1.1, 3, 2}, {1.5, 4, 2}};
  return kParams[severity - 1];
}

cv::Mat glass_blur_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const GlassParams p = glass_params(severity);
  // np.uint8(gaussian(...) * 255): the blurred values are within [0, 1], so the clip in
  // gaussian_blur_u8 changes nothing.
  cv::Mat img = nd::gaussian_blur_u8(bgr, p.sigma);
  shuffle_pixels(img, p, [&] { return static_cast<int>(rng.randint(-p.delta, p.delta)); });
  return nd::gaussian_blur_u8(img, p.sigma);
}

cv::Mat glass_blur_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const GlassParams p = glass_params(severity);
  // The fixed-point blur at every severity: against numpy mode's float64 blur alone it differs by
  // one level on 0.16-0.31 % of a 1600x900 frame's values at severities 1-5 (the float32 blur it
  // replaced: 0.20-0.26 %), and on 0-1.5 % of a linear ramp's (float32: 15.9 % at sigma 0.7 and
  // 0.9), at under half the float32 blur's cost.
  // (gaussian_blur's earlier dithered 8-bit blur was tried: it kept flat areas at their level
  // where the reference's float64 sums truncate some levels one down, and the histogram moved ten
  // times as far from numpy mode's as another seed's does; the flat table covers that here.)
  const FastBlur blur = fast_blur(p.sigma);
  // The first blur's image is scratch, one per thread (the same size frame after frame: no fresh
  // 4 MB of pages per frame).
  thread_local cv::Mat img;
  fixed_point_blur(bgr, blur.kernel, img, &blur.flat);
  walk_fast(img, p, rng);
  cv::Mat out;
  fixed_point_blur(img, blur.kernel, out, &blur.flat);
  return out;
}

}  // namespace faultline::corruption
