#include "detector/photometric.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace faultline::detector {
namespace {

using Histogram = std::array<int, 256>;

int percentile(const Histogram& h, int total, double p) {
  const double target = p * total;
  int acc = 0;
  for (int v = 0; v < 256; ++v) {
    acc += h[static_cast<std::size_t>(v)];
    if (acc > target) return v;
  }
  return 255;
}

bool over_exposed(const std::uint8_t* p, int clip_level) {
  return std::max({p[0], p[1], p[2]}) >= clip_level;
}

// Byte-wise first (vectorised): most rows of most frames have no channel at the clip level.
bool row_has_over_exposed(const std::uint8_t* row, int bytes, int clip_level) {
  std::uint8_t brightest = 0;
  for (int i = 0; i < bytes; ++i) brightest = std::max(brightest, row[i]);
  return brightest >= clip_level;
}

long count_over_exposed(const cv::Mat& input, int clip_level) {
  long clipped = 0;
  for (int y = 0; y < input.rows; ++y) {
    const std::uint8_t* p = input.ptr<std::uint8_t>(y);
    if (!row_has_over_exposed(p, 3 * input.cols, clip_level)) continue;
    for (int x = 0; x < input.cols; ++x) clipped += over_exposed(p + 3 * x, clip_level);
  }
  return clipped;
}

// Blacks out in `out` the pixels over-exposed in `input` (same size), judged before any stretch.
void black_out_over_exposed(const cv::Mat& input, cv::Mat& out, int clip_level) {
  for (int y = 0; y < input.rows; ++y) {
    const std::uint8_t* p = input.ptr<std::uint8_t>(y);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < input.cols; ++x)
      if (over_exposed(p + 3 * x, clip_level)) o[3 * x] = o[3 * x + 1] = o[3 * x + 2] = 0;
  }
}

}  // namespace

double estimate_noise_sigma(const cv::Mat& bgr) {
  CV_Assert(bgr.type() == CV_8UC3);
  auto sum = [&](int y, int x) {
    const std::uint8_t* p = bgr.ptr<std::uint8_t>(y) + 3 * x;
    return p[0] + p[1] + p[2];
  };
  std::vector<int> response;
  for (int y = 1; y + 1 < bgr.rows; y += 8)
    for (int x = 1; x + 1 < bgr.cols; x += 8) {
      const int v = sum(y - 1, x - 1) - 2 * sum(y - 1, x) + sum(y - 1, x + 1) - 2 * sum(y, x - 1) +
                    4 * sum(y, x) - 2 * sum(y, x + 1) + sum(y + 1, x - 1) - 2 * sum(y + 1, x) +
                    sum(y + 1, x + 1);
      response.push_back(std::abs(v));
    }
  if (response.empty()) return 0.0;
  auto mid = response.begin() + static_cast<std::ptrdiff_t>(response.size() / 2);
  std::nth_element(response.begin(), mid, response.end());
  // The mask's weights square-sum to 36, so its response to white noise has sigma 6 * sigma(sum of
  // 3 channels); the median of |N(0, s)| is 0.6745 s; and sigma(sum) = sqrt(3) * sigma(channel).
  return *mid / (0.6745 * 6.0) / std::sqrt(3.0);
}

cv::Mat normalise_photometric(const cv::Mat& bgr, const PhotometricConfig& config,
                              PhotometricStats* stats, cv::Mat* scratch) {
  CV_Assert(bgr.type() == CV_8UC3);
  PhotometricStats s;
  if (!config.enabled || bgr.empty()) {
    if (stats) *stats = s;
    return bgr;
  }
  Histogram dark{}, bright{};  // per pixel: min and max channel, on a 4-pixel grid
  int n = 0;
  for (int y = 0; y < bgr.rows; y += 4) {
    const std::uint8_t* p = bgr.ptr<std::uint8_t>(y);
    for (int x = 0; x < bgr.cols; x += 4) {
      const int b = p[3 * x], g = p[3 * x + 1], r = p[3 * x + 2];
      ++dark[static_cast<std::size_t>(std::min({b, g, r}))];
      ++bright[static_cast<std::size_t>(std::max({b, g, r}))];
      ++n;
    }
  }
  s.black = percentile(dark, n, config.black_percentile) * config.black_fraction;
  s.white = percentile(bright, n, 0.98);
  s.gain = std::clamp(config.white_level / std::max(1.0, s.white - s.black), 1.0, config.max_gain);
  s.noise_sigma = estimate_noise_sigma(bgr);

  cv::Mat input = bgr;
  if (s.noise_sigma * s.gain > config.noise_limit && bgr.cols >= 2 && bgr.rows >= 2) {
    s.bin = 2;
    cv::resize(bgr, input, cv::Size(bgr.cols / 2, bgr.rows / 2), 0, 0, cv::INTER_AREA);
  }
  const long clipped = count_over_exposed(input, config.clip_level);
  s.clipped_fraction =
      input.total() ? static_cast<double>(clipped) / static_cast<double>(input.total()) : 0.0;
  if (stats) *stats = s;
  const bool identity = s.black < 0.5 && s.gain <= 1.15;  // close enough: keep the exact pixels
  if (identity && clipped == 0) return input;

  cv::Mat local;
  cv::Mat& out = scratch ? *scratch : local;
  if (identity) {
    input.copyTo(out);
  } else {
    std::array<std::uint8_t, 256> curve{};
    for (int v = 0; v < 256; ++v)
      curve[static_cast<std::size_t>(v)] =
          cv::saturate_cast<std::uint8_t>(std::clamp((v - s.black) * s.gain, 0.0, 255.0));
    cv::LUT(input, cv::Mat(1, 256, CV_8U, curve.data()), out);
  }
  if (clipped > 0) black_out_over_exposed(input, out, config.clip_level);
  return out;
}

}  // namespace faultline::detector
