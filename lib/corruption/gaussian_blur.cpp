// gaussian_blur: scipy.ndimage's separable float64 correlation mirrored exactly, and a fixed-point
// fast path.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/simd.hpp"
#include "corruption/digital.hpp"
#include "corruption/fixed_point_blur.hpp"
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

// The reference's radius int(4 sigma + 0.5) less its outermost tap when it is even: the
// fixed-point blur sums its taps in pairs, the centre with the first, so an odd radius costs no
// more than the even one below it, and an even radius pays a whole pair for the outermost tap,
// whose weight is below exp(-8) of the centre's (1.3e-4 of the total at sigma 1, 6.7e-5 at 2).
int odd_radius(double sigma) {
  const int r = kernel_radius(sigma);
  return r % 2 == 0 && r > 1 ? r - 1 : r;
}

// An exact f x bilinear upscale samples the low image at (x + 0.5) / f - 0.5 (OpenCV's and PIL's
// pixel centres). Output phase q (x = f i + q) blends low pixels i + first and i + first + 1 with
// weights in units of 1 / (2 f).
struct PhaseTaps {
  int first;
  int w_first;
  int w_next;
};

PhaseTaps phase_taps(int q, int f) {
  const int offset = 2 * q + 1 - f;  // the sample's offset from low pixel i, in 1 / (2 f)
  if (offset < 0) return {-1, -offset, 2 * f + offset};
  return {0, 2 * f - offset, offset};
}

// v[i] = a[i] wa + b[i] wb: one phase of a low row, values scaled by 2 f.
FAULTLINE_CLONES("avx2")
void blend_pixels(std::uint16_t* v, const std::uint8_t* a, const std::uint8_t* b, std::uint16_t wa,
                  std::uint16_t wb, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    v[i] = static_cast<std::uint16_t>(static_cast<std::uint16_t>(a[i] * wa) +
                                      static_cast<std::uint16_t>(b[i] * wb));
  }
}

// out[i] = (a[i] wa + b[i] wb + offset) >> Shift, in 16 bits (the sums stay below 2^14 + offset;
// a constant shift keeps the vector loop in 16-bit lanes).
template <int Shift>
[[gnu::always_inline]] inline void blend_rows(std::uint8_t* out, const std::uint16_t* a,
                                              const std::uint16_t* b, std::uint16_t wa,
                                              std::uint16_t wb, std::uint16_t offset,
                                              std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const auto sum = static_cast<std::uint16_t>(static_cast<std::uint16_t>(a[i] * wa) +
                                                static_cast<std::uint16_t>(b[i] * wb) + offset);
    out[i] = static_cast<std::uint8_t>(sum >> Shift);
  }
}

// blend_rows for f = 2 ((2 f)^2 = 2^4) and f = 4 (2^6).
FAULTLINE_CLONES("avx2")
void blend_rows_2x(std::uint8_t* out, const std::uint16_t* a, const std::uint16_t* b,
                   std::uint16_t wa, std::uint16_t wb, std::uint16_t offset, std::size_t n) {
  blend_rows<4>(out, a, b, wa, wb, offset, n);
}

FAULTLINE_CLONES("avx2")
void blend_rows_4x(std::uint8_t* out, const std::uint16_t* a, const std::uint16_t* b,
                   std::uint16_t wa, std::uint16_t wb, std::uint16_t offset, std::size_t n) {
  blend_rows<6>(out, a, b, wa, wb, offset, n);
}

// Low rows upscaled f x along the row for output columns pad .. pad + cols - 1: each phase q
// blended with blend_pixels, then interleaved (output pixel x = f i + q is phase q's pixel i).
// The two most recent are kept: consecutive output rows share them.
class WideRows {
 public:
  WideRows(int f, int pad, int cols, int ch)
      : f_(f),
        base_(pad / f),
        cols_(cols),
        ch_(ch),
        low_pixels_(static_cast<std::size_t>((cols + f - 1) / f)),
        phase_(static_cast<std::size_t>(f) * (low_pixels_ + 1) * static_cast<std::size_t>(ch)) {
    for (auto& row : rows_)
      row.resize(static_cast<std::size_t>(cols) * static_cast<std::size_t>(ch) + 1);
  }

  const std::uint16_t* row(const cv::Mat& low, int j) {
    for (std::size_t k = 0; k < 2; ++k) {
      if (index_[k] == j) return rows_[k].data();
    }
    const std::size_t k = index_[0] < index_[1] ? 0 : 1;  // the older one
    widen(low.ptr<std::uint8_t>(j), rows_[k].data());
    index_[k] = j;
    return rows_[k].data();
  }

 private:
  void widen(const std::uint8_t* src, std::uint16_t* out) {
    const auto ch = static_cast<std::size_t>(ch_);
    const std::size_t n = low_pixels_ * ch, stride = (low_pixels_ + 1) * ch;
    for (int q = 0; q < f_; ++q) {
      const PhaseTaps t = phase_taps(q, f_);
      const std::uint8_t* a = src + static_cast<std::ptrdiff_t>((base_ + t.first) * ch_);
      blend_pixels(phase_.data() + static_cast<std::size_t>(q) * stride, a, a + ch,
                   static_cast<std::uint16_t>(t.w_first), static_cast<std::uint16_t>(t.w_next), n);
    }
    if (ch == 3 && f_ == 2) return interleave_bgr<2>(out, stride);
    if (ch == 3 && f_ == 4) return interleave_bgr<4>(out, stride);
    int x = 0;
    for (std::size_t i = 0; x < cols_; ++i) {
      for (int q = 0; q < f_ && x < cols_; ++q, ++x) {
        const std::uint16_t* p = phase_.data() + static_cast<std::size_t>(q) * stride + i * ch;
        std::copy(p, p + ch, out + static_cast<std::size_t>(x) * ch);
      }
    }
  }

  // Three channels as 8-byte copies (three values and the next pixel's first) in increasing x,
  // each rewritten by the next pixel's own copy; the last pixel copies its three alone.
  template <int F>
  void interleave_bgr(std::uint16_t* out, std::size_t stride) const {
    const std::uint16_t* p[F];
    for (int q = 0; q < F; ++q) p[q] = phase_.data() + static_cast<std::size_t>(q) * stride;
    const auto groups = static_cast<std::size_t>((cols_ - 1) / F);  // all before the last pixel
    for (std::size_t i = 0; i < groups; ++i) {
      for (int q = 0; q < F; ++q) std::memcpy(out + 3 * (F * i + q), p[q] + 3 * i, 8);
    }
    for (auto x = static_cast<std::size_t>(F) * groups; x < static_cast<std::size_t>(cols_); ++x) {
      std::copy(p[x % F] + 3 * (x / F), p[x % F] + 3 * (x / F) + 3, out + 3 * x);
    }
  }

  int f_, base_, cols_, ch_;
  std::size_t low_pixels_;
  std::vector<std::uint16_t> phase_;  // f rows of low_pixels_ + 1 pixels
  std::vector<std::uint16_t> rows_[2];
  int index_[2] = {-1, -1};
};

// The region (pad, pad, cols, rows) of `low` upscaled f x bilinearly (pad a multiple of f, at least
// f, so every sample has both neighbours): the crop of cv::resize(low, f x) computed alone, without
// the full-size intermediate and the copy out of it. The values are rounded 1/8 of a level low
// for f = 2 and 1/4 for f = 4 (exact values stay exact): that takes back, on average, what the
// block means' rounding half up added (1/8 of a level per halving).
cv::Mat upscale_crop(const cv::Mat& low, int f, int pad, int cols, int rows) {
  // (2 f)^2 = 2^shift; the offset is half of it less the bias.
  const auto offset = static_cast<std::uint16_t>(f == 2 ? 8 - 2 : 32 - 16);
  const auto n = static_cast<std::size_t>(cols) * static_cast<std::size_t>(low.channels());
  WideRows wide(f, pad, cols, low.channels());
  cv::Mat out(rows, cols, low.type());
  for (int y = 0; y < rows; ++y) {
    const PhaseTaps t = phase_taps(y % f, f);
    const int a = y / f + pad / f + t.first;
    const std::uint16_t* above = wide.row(low, a);
    const std::uint16_t* below = wide.row(low, a + 1);
    const auto wa = static_cast<std::uint16_t>(t.w_first),
               wb = static_cast<std::uint16_t>(t.w_next);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    (f == 2 ? blend_rows_2x : blend_rows_4x)(o, above, below, wa, wb, offset, n);
  }
  return out;
}

// Blur at 1 / f resolution: f x f block means (cv::INTER_AREA), the fixed-point blur with the
// sigma left after the blocks' variance (f^2 - 1) / 12 and the bilinear upsampling's (0.75 for
// f = 2, 2.75 for f = 4, averaged over the output phases), then bilinear back to full size.
// Variances add, so the whole is a Gaussian of `sigma` to within the shape of the small
// kernels; the blur removes the frequencies the block means fold back (its response at the
// folding frequency 1 / (2 f), exp(-pi^2 sigma^2 / (2 f^2)), is below 2e-5 here). The
// low-resolution kernel stops at 3 of its sigmas (0.3 % of its weight, renormalised).
cv::Mat reduced_blur(const cv::Mat& bgr, double sigma, int f) {
  const double up_var = f == 2 ? 0.75 : 2.75;
  const double low_sigma = std::sqrt(sigma * sigma - (f * f - 1) / 12.0 - up_var) / f;
  // The frame first gets the reference's border ('nearest': the edge pixel repeated) for the
  // kernel's reach, a whole number of blocks wide; block means of the border alone would repeat
  // the edge block instead, tens of levels off near a high-contrast edge. A side that is not a
  // multiple of f gets up to f - 1 more border after its end, so that every block is whole: a
  // stretched block grid shifts the frame by up to a few pixels at its far side (44 levels at a
  // 333 x 197 chart's edges).
  const int pad = (kernel_radius(sigma) + f - 1) / f * f;
  const int extra_x = (f - bgr.cols % f) % f, extra_y = (f - bgr.rows % f) % f;
  cv::Mat low;
  cv::copyMakeBorder(bgr, low, pad, pad + extra_y, pad, pad + extra_x, cv::BORDER_REPLICATE);
  for (int halving = f; halving > 1; halving /= 2) {
    cv::resize(low, low, cv::Size(low.cols / 2, low.rows / 2), 0, 0, cv::INTER_AREA);
  }
  // The blur truncates at low resolution; the bilinear upsampling's rounding then keeps the
  // truncated level on average.
  const int r = std::max(1, static_cast<int>(3.0 * low_sigma + 0.5)) | 1;  // see odd_radius
  cv::Mat blurred;
  fixed_point_blur(low, fixed_point_gaussian(low_sigma, r), blurred);
  return upscale_crop(blurred, f, pad, bgr.cols, bgr.rows);
}

}  // namespace

cv::Mat gaussian_blur_fast(const cv::Mat& bgr, int severity) {
  const double sigma = gaussian_blur_sigma(severity);
  // Reduced resolution from sigma 3 (sigma 2 stays at full resolution). Frames too small for 4 x
  // 4 blocks of a few pixels each way keep the full-resolution blur (it costs little there).
  const bool reduce = sigma >= 3.0 && bgr.rows >= 64 && bgr.cols >= 64;
  if (!reduce) {
    cv::Mat out;
    fixed_point_blur(bgr, fixed_point_gaussian(sigma, odd_radius(sigma)), out);
    return out;
  }
  return reduced_blur(bgr, sigma, sigma >= 6.0 ? 4 : 2);
}

}  // namespace faultline::corruption
