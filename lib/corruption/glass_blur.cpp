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

// out[i] = (chunk[i] * span) >> 16 - delta: OffsetStream's map, eight or sixteen at a time.
FAULTLINE_CLONES("avx2")
void map_chunks(std::int8_t* out, const std::uint16_t* chunk, std::size_t n, std::uint32_t span,
                int delta) {
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = static_cast<std::int8_t>(static_cast<int>((chunk[i] * span) >> 16) - delta);
  }
}

// fast mode's offsets: four to a 64-bit draw, 16 bits each, scaled to [-d, d) by multiply and
// shift (uniform for d = 1, 2, 4; for d = 3 four of the six values are 1 / 10922 more likely than
// the other two, far below anything the output shows). Drawn a row at a time, in the walk's order.
class OffsetStream {
 public:
  OffsetStream(rng::FastRng& rng, int delta)
      : rng_(rng), delta_(delta), span_(static_cast<std::uint64_t>(2 * delta)) {}
  void fill(std::int8_t* out, std::size_t n) {
    std::size_t i = 0;
    for (; i < n && left_ > 0; ++i) out[i] = take();
    // The whole words' chunks first (the draws are serial), then mapped in one vector loop.
    const std::size_t words = (n - i) / 4;
    chunks_.resize(4 * words);
    for (std::size_t j = 0; j < words; ++j) {
      const std::uint64_t w = rng_.next_u64();
      for (std::size_t k = 0; k < 4; ++k)
        chunks_[4 * j + k] = static_cast<std::uint16_t>(w >> (16 * k));
    }
    map_chunks(out + i, chunks_.data(), chunks_.size(), static_cast<std::uint32_t>(span_), delta_);
    i += chunks_.size();
    for (; i < n; ++i) out[i] = take();
  }

 private:
  std::int8_t map(std::uint64_t chunk) const {
    return static_cast<std::int8_t>(static_cast<int>(((chunk & 0xFFFFu) * span_) >> 16) - delta_);
  }
  std::int8_t take() {
    if (left_ == 0) word_ = rng_.next_u64(), left_ = 4;
    const std::int8_t v = map(word_);
    word_ >>= 16, --left_;
    return v;
  }
  rng::FastRng& rng_;
  int delta_;
  std::uint64_t span_;
  std::uint64_t word_ = 0;
  int left_ = 0;
  std::vector<std::uint16_t> chunks_;
};

// shuffle_pixels with OffsetStream's draws (dx, then dy, per pixel), a row's offsets drawn and
// turned into byte offsets before its serial copy loop (a copy may read a pixel the walk wrote).
void walk_fast(cv::Mat& img, const GlassParams& p, rng::FastRng& rng) {
  const int d = p.delta;
  if (img.cols - 2 * d <= 0) return;
  const auto count = static_cast<std::size_t>(img.cols - 2 * d);
  std::vector<std::int8_t> draws(2 * count);
  std::vector<std::ptrdiff_t> offset(count);
  const auto step = static_cast<std::ptrdiff_t>(img.step[0]);
  OffsetStream stream(rng, d);
  for (int it = 0; it < p.iterations; ++it) {
    for (int h = img.rows - d; h > d; --h) {
      stream.fill(draws.data(), draws.size());
      for (std::size_t k = 0; k < count; ++k)
        offset[k] = draws[2 * k + 1] * step + 3 * draws[2 * k];
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
