// gaussian_blur: scipy.ndimage's separable float64 correlation mirrored exactly, and a fixed-point
// fast path.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/simd.hpp"
#include "corruption/digital.hpp"
#include "corruption/ndimage.hpp"

namespace faultline::corruption {
namespace {

// scipy's _gaussian_kernel1d(sigma, 0, radius): exp(-0.5 / sigma^2 * x^2) for x = -radius..radius,
// divided by its numpy sum. Index radius + j holds the weight of offset j (the kernel is exactly
// symmetric). The exp is NumPy's (nd::numpy_exp): glibc's differs by an ulp on some of these
// arguments, which moves truncated outputs.
std::vector<double> gaussian_kernel(double sigma, int radius) {
  std::vector<double> phi(static_cast<std::size_t>(2 * radius + 1));
  const double k = -0.5 / (sigma * sigma);
  for (int x = -radius; x <= radius; ++x) {
    phi[static_cast<std::size_t>(x + radius)] = nd::numpy_exp(k * static_cast<double>(x * x));
  }
  const double sum = nd::pairwise_sum(phi.data(), phi.size());
  for (double& w : phi) w = w / sum;
  return phi;
}

int kernel_radius(double sigma) { return static_cast<int>(4.0 * sigma + 0.5); }

// One output line of NI_Correlate1D's symmetric branch: out[i] = in[i] * w0, then += (in[i - j] +
// in[i + j]) * w_j for j = radius..1. `in` points at element 0 of a line padded by radius * step on
// both sides; elements are `step` apart, and `count` consecutive outputs are made (all elements of
// a padded row at once: step = 3 for a row of BGR pixels, or 1 across columns of stacked rows).
void correlate_line(const double* in, double* out, std::size_t count, std::ptrdiff_t step,
                    const std::vector<double>& w, int radius) {
  const double w0 = w[static_cast<std::size_t>(radius)];
  for (std::size_t i = 0; i < count; ++i) out[i] = in[i] * w0;
  for (int j = radius; j >= 1; --j) {
    const double wj = w[static_cast<std::size_t>(radius - j)];
    const double* lo = in - j * step;
    const double* hi = in + j * step;
    for (std::size_t i = 0; i < count; ++i) out[i] += (lo[i] + hi[i]) * wj;
  }
}

}  // namespace

double gaussian_blur_sigma(int severity) {
  static constexpr double kS[] = {1, 2, 3, 4, 6};
  return kS[static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1)];
}

cv::Mat gaussian_blur_exact(const cv::Mat& bgr, int severity) {
  const double sigma = gaussian_blur_sigma(severity);
  return detail::gaussian_blur_weights(bgr, gaussian_kernel(sigma, kernel_radius(sigma)));
}

namespace detail {

std::vector<double> normalized_kernel(const std::vector<double>& phi) {
  const double sum = nd::pairwise_sum(phi.data(), phi.size());
  std::vector<double> w(phi);
  for (double& v : w) v = v / sum;
  return w;
}

cv::Mat gaussian_blur_weights(const cv::Mat& bgr, const std::vector<double>& w) {
  const int r = static_cast<int>(w.size() / 2);
  const int rows = bgr.rows, cols = bgr.cols;
  const std::size_t row_len = static_cast<std::size_t>(cols) * 3;
  // Pass 1 (axis 0): every row of the output from the rows above and below, edge rows replicated
  // ('nearest').
  std::vector<double> x(static_cast<std::size_t>(rows) * row_len);
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* src = bgr.ptr<std::uint8_t>(y);
    for (std::size_t e = 0; e < row_len; ++e)
      x[static_cast<std::size_t>(y) * row_len + e] = src[e] / 255.0;
  }
  std::vector<double> pass1(x.size());
  std::vector<const double*> padded(static_cast<std::size_t>(rows + 2 * r));
  for (int k = 0; k < rows + 2 * r; ++k) {
    padded[static_cast<std::size_t>(k)] =
        x.data() + static_cast<std::size_t>(std::clamp(k - r, 0, rows - 1)) * row_len;
  }
  const double w0 = w[static_cast<std::size_t>(r)];
  for (int y = 0; y < rows; ++y) {
    double* out = pass1.data() + static_cast<std::size_t>(y) * row_len;
    const double* mid = padded[static_cast<std::size_t>(y + r)];
    for (std::size_t e = 0; e < row_len; ++e) out[e] = mid[e] * w0;
    for (int j = r; j >= 1; --j) {
      const double wj = w[static_cast<std::size_t>(r - j)];
      const double* above = padded[static_cast<std::size_t>(y + r - j)];
      const double* below = padded[static_cast<std::size_t>(y + r + j)];
      for (std::size_t e = 0; e < row_len; ++e) out[e] += (above[e] + below[e]) * wj;
    }
  }
  // Pass 2 (axis 1): along each row, the first and last pixel replicated r times.
  cv::Mat out(rows, cols, CV_8UC3);
  std::vector<double> line((static_cast<std::size_t>(cols) + 2 * static_cast<std::size_t>(r)) * 3);
  std::vector<double> res(row_len);
  for (int y = 0; y < rows; ++y) {
    const double* src = pass1.data() + static_cast<std::size_t>(y) * row_len;
    for (int k = 0; k < cols + 2 * r; ++k) {
      const double* px = src + static_cast<std::size_t>(std::clamp(k - r, 0, cols - 1)) * 3;
      std::copy(px, px + 3, line.data() + static_cast<std::size_t>(k) * 3);
    }
    correlate_line(line.data() + static_cast<std::size_t>(r) * 3, res.data(), row_len, 3, w, r);
    std::uint8_t* dst = out.ptr<std::uint8_t>(y);
    for (std::size_t e = 0; e < row_len; ++e) {
      dst[e] = static_cast<std::uint8_t>(std::min(std::max(res[e], 0.0), 1.0) * 255.0);
    }
  }
  return out;
}

}  // namespace detail

namespace {

// dst = src - 1 (saturating at 0) where the dither pattern of row y holds a one: the pixels whose
// x + y is even, except two in every 8 x 8 tile, (0, 0) and (4, 4) (30 ones per 64 pixels).
FAULTLINE_CLONES("avx2")
void subtract_dither(std::uint8_t* dst, const std::uint8_t* src, std::size_t pixels, int y) {
  for (std::size_t x = 0; x < pixels; ++x) {
    const auto xi = static_cast<int>(x & 7u);
    const int yi = y & 7;
    const bool one = ((xi + yi) & 1) == 0 && !(xi == yi && (xi & 3) == 0);
    for (std::size_t c = 0; c < 3; ++c) {
      const std::uint8_t v = src[3 * x + c];
      dst[3 * x + c] = static_cast<std::uint8_t>(v - std::min<std::uint8_t>(v, one ? 1 : 0));
    }
  }
}

}  // namespace

cv::Mat gaussian_blur_fast(const cv::Mat& bgr, int severity) {
  const double sigma = gaussian_blur_sigma(severity);
  const int r = kernel_radius(sigma);
  // OpenCV's 8-bit Gaussian is fixed-point (16-bit weights and sums, the same taps and 'nearest'
  // border) and rounds, where the reference truncates: floor(x) = round(x - b) for 0 < b <= 1/2
  // wherever frac(x) < b + 1/2. A dither pattern of ones subtracted before the blur blurs to b =
  // 0.45-0.49 for sigma >= 1 (a checkerboard, whose frequency the blur removes, thinned so that b
  // stays below 1/2 despite the fixed-point weights): flat areas keep their value, and a value is
  // one too high only where frac(x) >= b + 1/2 (a few %, never more than one level).
  cv::Mat shifted(bgr.size(), CV_8UC3), out;
  for (int y = 0; y < bgr.rows; ++y) {
    subtract_dither(shifted.ptr<std::uint8_t>(y), bgr.ptr<std::uint8_t>(y),
                    static_cast<std::size_t>(bgr.cols), y);
  }
  cv::GaussianBlur(shifted, out, cv::Size(2 * r + 1, 2 * r + 1), sigma, sigma,
                   cv::BORDER_REPLICATE);
  return out;
}

}  // namespace faultline::corruption
