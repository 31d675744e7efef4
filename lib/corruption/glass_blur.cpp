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

// skimage gaussian of u8 / 255 (float64, per channel, edge-replicating): the float64 result.
cv::Mat blur_unit(const cv::Mat& bgr, double sigma) {
  cv::Mat x(bgr.size(), CV_64FC3);
  for (int y = 0; y < bgr.rows; ++y) {
    const unsigned char* s = bgr.ptr<unsigned char>(y);
    double* d = x.ptr<double>(y);
    for (int i = 0; i < bgr.cols * 3; ++i) d[i] = s[i] / 255.0;
  }
  nd::gaussian_filter(x, sigma, sigma, nd::Extend::Nearest);
  return x;
}

cv::Mat truncate_to_u8(const cv::Mat& m, double scale) {
  cv::Mat out(m.size(), CV_8UC3);
  const int width = m.cols * 3;
  for (int y = 0; y < m.rows; ++y) {
    unsigned char* o = out.ptr<unsigned char>(y);
    const double* s = m.ptr<double>(y);
    for (int i = 0; i < width; ++i) o[i] = static_cast<unsigned char>(std::min(std::max(s[i], 0.0), 1.0) * scale);
  }
  return out;
}

}  // namespace

GlassParams glass_params(int severity) {
  static constexpr GlassParams kParams[] = {{0.7, 1, 2}, {0.9, 2, 1}, {1, 2, 3}, {1.1, 3, 2}, {1.5, 4, 2}};
  return kParams[severity - 1];
}

cv::Mat glass_blur_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const GlassParams p = glass_params(severity);
  // np.uint8(gaussian(...) * 255): the blurred values are within [0, 1], so clipping changes nothing.
  cv::Mat img = truncate_to_u8(blur_unit(bgr, p.sigma), 255.0);
  shuffle_pixels(img, p, [&] { return static_cast<int>(rng.randint(-p.delta, p.delta)); });
  return truncate_to_u8(blur_unit(img, p.sigma), 255.0);
}

cv::Mat glass_blur_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const GlassParams p = glass_params(severity);
  // The blurs are numpy mode's: a float32 blur truncates flat areas differently (the reference's float64 sums land
  // a hair below or on an integer), which moved ~9 % of the histogram at severity 5; the pixel walk dominates the
  // cost of the reference, not the blurs.
  cv::Mat img = truncate_to_u8(blur_unit(bgr, p.sigma), 255.0);
  const auto span = static_cast<std::uint32_t>(2 * p.delta);
  shuffle_pixels(img, p, [&] { return static_cast<int>(rng.bounded(span)) - p.delta; });
  return truncate_to_u8(blur_unit(img, p.sigma), 255.0);
}

}  // namespace faultline::corruption
