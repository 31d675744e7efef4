// Lens soiling: blobs of Gaussian lobes on a 1/8-resolution grid, upsampled once; the scene behind
// them blurred and tinted at 1/8 resolution per frame.
#include "corruption/soiling.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "corruption/grid_upsample.hpp"
#include "rng/fast_rng.hpp"

namespace faultline::corruption {
namespace {

constexpr int kGridDivisor =
    8;  // the dirt is far out of focus: 1/8 resolution carries all its detail
// Reflectance of dried mud in B, G, R: the light the dirt absorbs leaves it brown.
constexpr double kDirtTint[3] = {0.22, 0.30, 0.38};

double smoothstep(double lo, double hi, double v) {
  const double t = std::clamp((v - lo) / (hi - lo), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

cv::Size grid_size(cv::Size size) {
  return {std::max(1, (size.width + kGridDivisor - 1) / kGridDivisor),
          std::max(1, (size.height + kGridDivisor - 1) / kGridDivisor)};
}

// Opacity (0..1) on the grid: each blob is the union of 3-5 offset Gaussian lobes, roughened by a
// grid noise and cut with a soft threshold, at its own opacity; overlapping blobs take the larger
// opacity.
cv::Mat draw_blobs(const SoilingParams& p, std::uint64_t seed, cv::Size size) {
  rng::FastRng rng(seed);
  const cv::Size g = grid_size(size);
  const double sx = static_cast<double>(size.width) / g.width,
               sy = static_cast<double>(size.height) / g.height;
  cv::Mat noise(g, CV_64F);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) noise.at<double>(y, x) = rng.uniform(-0.12, 0.12);
  }
  cv::Mat alpha(g, CV_64F, cv::Scalar(0));
  const double area = static_cast<double>(size.width) * size.height;
  const double base_r = std::sqrt(p.coverage * area / (p.blobs * M_PI));
  for (int b = 0; b < p.blobs; ++b) {
    const double cx = rng.uniform(0, size.width), cy = rng.uniform(0, size.height);
    const double r = base_r * rng.uniform(0.7, 1.3);
    const double opacity = p.opacity * rng.uniform(0.75, 1.0);
    const int lobes = 3 + static_cast<int>(rng.bounded(3));
    double lx[5], ly[5], ls[5];
    for (int k = 0; k < lobes; ++k) {
      lx[k] = cx + 0.45 * r * rng.uniform(-1, 1);
      ly[k] = cy + 0.45 * r * rng.uniform(-1, 1);
      ls[k] = std::max(1e-3, r * rng.uniform(0.45, 0.75));
    }
    // Only cells within reach of a lobe: beyond 2.1 sd a lobe stays under the threshold whatever
    // the noise.
    const double reach = 0.45 * r + 2.1 * 0.75 * r;
    const int gx0 = std::max(0, static_cast<int>(std::floor((cx - reach) / sx)));
    const int gx1 = std::min(g.width, static_cast<int>(std::ceil((cx + reach) / sx)) + 1);
    const int gy0 = std::max(0, static_cast<int>(std::floor((cy - reach) / sy)));
    const int gy1 = std::min(g.height, static_cast<int>(std::ceil((cy + reach) / sy)) + 1);
    for (int y = gy0; y < gy1; ++y) {
      const double py = (y + 0.5) * sy;
      for (int x = gx0; x < gx1; ++x) {
        const double px = (x + 0.5) * sx;
        double q = 1e30;  // the largest lobe is the smallest exponent: one exp per cell
        for (int k = 0; k < lobes; ++k) {
          const double d2 = (px - lx[k]) * (px - lx[k]) + (py - ly[k]) * (py - ly[k]);
          q = std::min(q, d2 / (2 * ls[k] * ls[k]));
        }
        const double a = opacity * smoothstep(0.25, 0.75, std::exp(-q) + noise.at<double>(y, x));
        double& cell = alpha.at<double>(y, x);
        cell = std::max(cell, a);
      }
    }
  }
  return alpha;
}

}  // namespace

SoilingParams soiling_params(int severity) {
  static const SoilingParams kTable[] = {{2, 0.02, 0.45, 0.60},
                                         {4, 0.05, 0.65, 0.45},
                                         {6, 0.10, 0.80, 0.35},
                                         {9, 0.18, 0.90, 0.25},
                                         {12, 0.30, 0.97, 0.15}};
  return kTable[std::clamp(severity, 1, 5) - 1];
}

SoilingModel::SoilingModel(int severity, std::uint64_t seed, cv::Size size)
    : params_(soiling_params(severity)) {
  cv::Mat grid8;
  draw_blobs(params_, seed, size).convertTo(grid8, CV_8U, 255.0);
  cv::resize(grid8, alpha_, size, 0, 0, cv::INTER_LINEAR);
  spans_.assign(static_cast<std::size_t>(size.height), {0, 0});
  int x0 = size.width, x1 = 0, y0 = size.height, y1 = 0;
  for (int y = 0; y < size.height; ++y) {
    const uchar* a = alpha_.ptr<uchar>(y);
    int first = 0, last = size.width;
    while (first < last && a[first] == 0) ++first;
    while (last > first && a[last - 1] == 0) --last;
    spans_[static_cast<std::size_t>(y)] = {first, last};
    if (first < last) {
      x0 = std::min(x0, first), x1 = std::max(x1, last);
      y0 = std::min(y0, y), y1 = y + 1;
    }
  }
  box_ = x0 < x1 ? cv::Rect(x0, y0, x1 - x0, y1 - y0) : cv::Rect();
}

cv::Mat SoilingModel::apply(const cv::Mat& bgr) const {
  cv::Mat out = bgr.clone();
  if (box_.empty()) return out;
  // What the dirt passes on: the scene scattered (blurred) and partly absorbed (tinted), at 1/8
  // resolution. Three pyramid steps give the grid's size (ceil(n / 8)) with the Gaussian blur built
  // in.
  cv::Mat small = bgr;
  for (int i = 0; i < 3; ++i)
    cv::pyrDown(small, small, cv::Size((small.cols + 1) / 2, (small.rows + 1) / 2));
  const double t = params_.transmission;
  cv::multiply(small,
               cv::Scalar(t + (1 - t) * kDirtTint[0], t + (1 - t) * kDirtTint[1],
                          t + (1 - t) * kDirtTint[2]),
               small);
  GridUpsampler up(small.size(), bgr.size());
  up.set_grid(small);
  std::vector<uchar> behind(static_cast<std::size_t>(3 * bgr.cols));
  for (int y = box_.y; y < box_.y + box_.height; ++y) {
    const auto [first, last] = spans_[static_cast<std::size_t>(y)];
    up.row(y, first, last, behind.data());
    const uchar* a = alpha_.ptr<uchar>(y);
    const uchar* s = bgr.ptr<uchar>(y);
    uchar* o = out.ptr<uchar>(y);
    for (int x = first; x < last; ++x) {
      const unsigned w = a[x];
      for (int c = 0; c < 3; ++c) {
        const int i = 3 * x + c;
        o[i] = static_cast<uchar>(
            (s[i] * (255u - w) + behind[static_cast<std::size_t>(i)] * w + 127u) / 255u);
      }
    }
  }
  return out;
}

}  // namespace faultline::corruption
