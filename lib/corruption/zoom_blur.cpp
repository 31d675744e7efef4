// Zoom Blur: the reference's float32 layer sum (exact) and an 8-bit cascaded fast path.
#include "corruption/zoom_blur.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

#include "corruption/ndimage.hpp"
#include "corruption/zoom_average.hpp"

namespace faultline::corruption {

namespace {

struct Arange {
  double start, stop, step;
};

// np.arange(start, stop, step) for floats: length ceil((stop - start) / step), a[1] = start + step,
// then a[i] = start + i * (a[1] - a[0]).
std::vector<double> arange(const Arange& r) {
  const auto n = static_cast<std::size_t>(std::ceil((r.stop - r.start) / r.step));
  std::vector<double> out(n);
  if (n == 0) return out;
  out[0] = r.start;
  if (n == 1) return out;
  out[1] = r.start + r.step;
  const double delta = out[1] - out[0];
  for (std::size_t i = 2; i < n; ++i) out[i] = r.start + static_cast<double>(i) * delta;
  return out;
}

// The reference's crop for one factor: ceil(len / z) samples from (len - that) // 2.
struct Crop {
  int top, left, rows, cols, out_rows, out_cols;
};

int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

Crop crop_for(int rows, int cols, double z) {
  Crop c;
  c.rows = static_cast<int>(std::ceil(rows / z));
  c.cols = static_cast<int>(std::ceil(cols / z));
  c.top = floor_div(rows - c.rows, 2);
  c.left = floor_div(cols - c.cols, 2);
  c.out_rows = static_cast<int>(std::nearbyint(c.rows * z));  // Python round(): half to even
  c.out_cols = static_cast<int>(std::nearbyint(c.cols * z));
  return c;
}

}  // namespace

std::vector<double> zoom_blur_factors(int severity) {
  static constexpr Arange kRanges[] = {
      {1, 1.11, 0.01}, {1, 1.16, 0.01}, {1, 1.21, 0.02}, {1, 1.26, 0.02}, {1, 1.31, 0.03}};
  return arange(kRanges[severity - 1]);
}

cv::Mat zoom_blur_exact(const cv::Mat& bgr, int severity) {
  const auto factors = zoom_blur_factors(severity);
  const int rows = bgr.rows, cols = bgr.cols;
  cv::Mat x(bgr.size(), CV_32FC3);
  for (int y = 0; y < rows; ++y) {
    const unsigned char* s = bgr.ptr<unsigned char>(y);
    float* d = x.ptr<float>(y);
    for (int i = 0; i < cols * 3; ++i) d[i] = static_cast<float>(s[i] / 255.0);
  }
  cv::Mat sum = cv::Mat::zeros(bgr.size(), CV_32FC3);
  for (const double z : factors) {
    const Crop c = crop_for(rows, cols, z);
    // A crop larger than the image (a factor below 1) cannot occur with these factors; clamp
    // defensively.
    const cv::Rect roi = cv::Rect(c.left, c.top, c.cols, c.rows) & cv::Rect(0, 0, cols, rows);
    const cv::Mat layer = nd::zoom_linear(x(roi), c.out_rows, c.out_cols);
    const int h = std::min(rows, layer.rows), w = std::min(cols, layer.cols);
    for (int y = 0; y < h; ++y) {
      const float* l = layer.ptr<float>(y);
      float* s = sum.ptr<float>(y);
      for (int i = 0; i < w * 3; ++i) s[i] += l[i];
    }
  }
  const auto n = static_cast<float>(factors.size() + 1);
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < rows; ++y) {
    const float* a = x.ptr<float>(y);
    const float* s = sum.ptr<float>(y);
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int i = 0; i < cols * 3; ++i) {
      const float v = (a[i] + s[i]) / n;
      o[i] = static_cast<unsigned char>(std::min(std::max(v, 0.f), 1.f) * 255.f);
    }
  }
  return out;
}

namespace {

// fast mode's four zoom factors: the mean of 16 layers scaled by every product of a subset of them
// approximates the reference's layers (the image twice, then each factor once) as a distribution
// of log scales. Layer c (0..15) is scaled by exp(sum of e_l over the bits l of c); the e_l are the
// least-squares fit of those sums to the reference's log scales at the quantiles (c + 0.5) / 16.
std::array<double, 4> cascade_factors(int severity) {
  std::vector<double> t{0.0};  // the image itself is the first layer too
  for (const double z : zoom_blur_factors(severity)) t.push_back(std::log(z));
  std::sort(t.begin(), t.end());
  const double n = static_cast<double>(t.size());
  std::array<double, 4> b{};
  for (int c = 0; c < 16; ++c) {
    const double pos = std::clamp((c + 0.5) / 16.0 * n - 0.5, 0.0, n - 1.0);
    const auto lo = static_cast<std::size_t>(pos);
    const std::size_t hi = std::min(lo + 1, t.size() - 1);
    const double target = t[lo] + (pos - static_cast<double>(lo)) * (t[hi] - t[lo]);
    for (int l = 0; l < 4; ++l) b[static_cast<std::size_t>(l)] += (c >> l & 1) ? target : 0.0;
  }
  // Normal equations 4 (I + J) e = b (each bit set in 8 layers, each pair in 4): e = (b - sum(b)
  // / 5) / 4.
  const double sum_b = b[0] + b[1] + b[2] + b[3];
  std::array<double, 4> z{};
  for (std::size_t l = 0; l < 4; ++l) z[l] = std::exp((b[l] - sum_b / 5.0) / 4.0);
  return z;
}

}  // namespace

cv::Mat zoom_blur_fast(const cv::Mat& bgr, int severity) {
  // Four halvings A <- (A + zoom(A)) / 2, each zoom the reference's crop-and-scale geometry for its
  // factor, fused into one 8-bit pass each (zoom_average): 4 passes instead of 11 to 16 zooms.
  // Each mean rounds; down, up, down, down by a quarter level on average adds up to about -0.5,
  // the reference's final truncation (flat areas stay exact).
  static constexpr int kBias[4] = {32, 96, 32, 32};
  // Two frames per thread for the steps between (fresh 4 MB pages per frame cost more than a pass).
  thread_local cv::Mat ping, pong;
  const std::array<double, 4> factors = cascade_factors(severity);
  cv::Mat out;
  const cv::Mat* a = &bgr;
  for (std::size_t step = 0; step < factors.size(); ++step) {
    const Crop c = crop_for(bgr.rows, bgr.cols, factors[step]);
    const cv::Rect roi =
        cv::Rect(c.left, c.top, c.cols, c.rows) & cv::Rect(0, 0, bgr.cols, bgr.rows);
    cv::Mat& dst = step + 1 == factors.size() ? out : (step % 2 == 0 ? ping : pong);
    zoom_average(*a, roi, cv::Size(c.out_cols, c.out_rows), kBias[step], dst);
    a = &dst;
  }
  return out;
}

}  // namespace faultline::corruption
