// Glass Blur: blur, local pixel copies in the reference's order, blur.
#include "corruption/glass_blur.hpp"

#include <algorithm>

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
  // The blurs are numpy mode's: a float32 blur truncates flat areas differently (the reference's
  // float64 sums land a hair below or on an integer), which moved ~9 % of the histogram at severity
  // 5; the pixel walk dominates the cost of the reference, not the blurs.
  cv::Mat img = nd::gaussian_blur_u8(bgr, p.sigma);
  const auto span = static_cast<std::uint32_t>(2 * p.delta);
  shuffle_pixels(img, p, [&] { return static_cast<int>(rng.bounded(span)) - p.delta; });
  return nd::gaussian_blur_u8(img, p.sigma);
}

}  // namespace faultline::corruption
