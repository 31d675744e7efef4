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

// The dither pattern: a one at the pixels whose x + y is even, except two in every 8 x 8 tile, (0,
// 0) and (4, 4) (30 ones per 64 pixels); row phase y & 7, all three channels of a pixel alike.
std::vector<std::uint8_t> dither_row(std::size_t pixels, int phase) {
  std::vector<std::uint8_t> row(3 * pixels);
  for (std::size_t x = 0; x < pixels; ++x) {
    const auto xi = static_cast<int>(x & 7u);
    const bool one = ((xi + phase) & 1) == 0 && !(xi == phase && (xi & 3) == 0);
    for (std::size_t c = 0; c < 3; ++c) row[3 * x + c] = one ? 1 : 0;
  }
  return row;
}

// dst = src - pattern, saturating at 0.
FAULTLINE_CLONES("avx2")
void subtract_saturating(std::uint8_t* dst, const std::uint8_t* src, const std::uint8_t* pattern,
                         std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    dst[i] = static_cast<std::uint8_t>(src[i] - std::min(src[i], pattern[i]));
  }
}

// The dithered 8-bit blur with a kernel of radius r.
cv::Mat dithered_blur(const cv::Mat& bgr, double sigma, int r) {
  // OpenCV's 8-bit Gaussian is fixed-point (16-bit weights and sums, the same taps and 'nearest'
  // border) and rounds, where the reference truncates: floor(x) = round(x - b) for 0 < b <= 1/2
  // wherever frac(x) < b + 1/2. A dither pattern of ones subtracted before the blur blurs to b =
  // 0.45-0.49 (a checkerboard, whose frequency the blur removes, thinned so that b
  // stays below 1/2 despite the fixed-point weights): flat areas keep their value, and a value is
  // one too high only where frac(x) >= b + 1/2 (a few %, never more than one level).
  const auto pixels = static_cast<std::size_t>(bgr.cols);
  std::vector<std::vector<std::uint8_t>> pattern;
  for (int phase = 0; phase < 8; ++phase) pattern.push_back(dither_row(pixels, phase));
  cv::Mat shifted(bgr.size(), CV_8UC3), out;
  for (int y = 0; y < bgr.rows; ++y) {
    subtract_saturating(shifted.ptr<std::uint8_t>(y), bgr.ptr<std::uint8_t>(y),
                        pattern[static_cast<std::size_t>(y & 7)].data(), 3 * pixels);
  }
  // Not in place: OpenCV 4.6 then leaves its fixed-point path (5x slower at sigma 1).
  cv::GaussianBlur(shifted, out, cv::Size(2 * r + 1, 2 * r + 1), sigma, sigma,
                   cv::BORDER_REPLICATE);
  return out;
}

// Blur at 1 / f resolution: f x f block means (cv::INTER_AREA), the dithered blur with the sigma
// left after the blocks' variance (f^2 - 1) / 12 and the bilinear upsampling's (0.75 for f =
// 2, 2.75 for f = 4, averaged over the output phases), then bilinear back to full size. Variances
// add, so the whole is a Gaussian of `sigma` to within the shape of the small kernels; the blur
// removes the frequencies the block means fold back (its response at the folding frequency 1 / (2
// f), exp(-pi^2 sigma^2 / (2 f^2)), is below 2e-5 here). The low-resolution kernel stops at 3 of
// its sigmas (0.3 % of its weight; OpenCV renormalises).
cv::Mat reduced_blur(const cv::Mat& bgr, double sigma, int f) {
  const double up_var = f == 2 ? 0.75 : 2.75;
  const double low_sigma = std::sqrt(sigma * sigma - (f * f - 1) / 12.0 - up_var) / f;
  // The frame first gets the reference's border ('nearest': the edge pixel repeated) for the
  // kernel's reach, a whole number of blocks wide; block means of the border alone would repeat
  // the edge block instead, tens of levels off near a high-contrast edge.
  const int pad = (kernel_radius(sigma) + f - 1) / f * f;
  cv::Mat low;
  cv::copyMakeBorder(bgr, low, pad, pad, pad, pad, cv::BORDER_REPLICATE);
  cv::resize(low, low, cv::Size((low.cols + 1) / 2, (low.rows + 1) / 2), 0, 0, cv::INTER_AREA);
  if (f == 4) {
    cv::resize(low, low, cv::Size((low.cols + 1) / 2, (low.rows + 1) / 2), 0, 0, cv::INTER_AREA);
  }
  // The dithered blur truncates at low resolution; the bilinear upsampling's rounding then keeps
  // the truncated level on average. (Upsampling only the frame's own blocks, a view, took OpenCV's
  // resize off its fast path: 3x slower.)
  const int r = std::max(1, static_cast<int>(3.0 * low_sigma + 0.5));
  const cv::Mat blurred = dithered_blur(low, low_sigma, r);
  cv::Mat up;
  cv::resize(blurred, up, cv::Size(blurred.cols * f, blurred.rows * f), 0, 0, cv::INTER_LINEAR);
  return up(cv::Rect(pad, pad, bgr.cols, bgr.rows)).clone();
}

}  // namespace

cv::Mat dithered_gaussian_blur(const cv::Mat& bgr, double sigma) {
  return dithered_blur(bgr, sigma, kernel_radius(sigma));
}

cv::Mat gaussian_blur_fast(const cv::Mat& bgr, int severity) {
  const double sigma = gaussian_blur_sigma(severity);
  // Reduced resolution from sigma 3, where the low-resolution sigma is at least 1.4 (below 1 the
  // dither's checkerboard survives the blur and flat areas lose a level; sigma 2 stays at full
  // resolution). Frames too small for 4 x 4 blocks of a few pixels each way keep the
  // full-resolution blur (it costs little there).
  const bool reduce = sigma >= 3.0 && bgr.rows >= 64 && bgr.cols >= 64;
  if (!reduce) return dithered_gaussian_blur(bgr, sigma);
  return reduced_blur(bgr, sigma, sigma >= 6.0 ? 4 : 2);
}

}  // namespace faultline::corruption
