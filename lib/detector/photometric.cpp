#include "detector/photometric.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
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

// Blacks out over-exposed pixels, judged on the input (before any stretch).
void black_out_clipped(const cv::Mat& input, cv::Mat& out, int clip_level, PhotometricStats& s) {
  long clipped = 0;
  for (int y = 0; y < input.rows; ++y) {
    const std::uint8_t* p = input.ptr<std::uint8_t>(y);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < input.cols; ++x) {
      if (std::max({p[3 * x], p[3 * x + 1], p[3 * x + 2]}) >= clip_level) {
        o[3 * x] = o[3 * x + 1] = o[3 * x + 2] = 0;
        ++clipped;
      }
    }
  }
  s.clipped_fraction = input.total() ? static_cast<double>(clipped) / static_cast<double>(input.total()) : 0.0;
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
      const int v = sum(y - 1, x - 1) - 2 * sum(y - 1, x) + sum(y - 1, x + 1) - 2 * sum(y, x - 1) + 4 * sum(y, x) -
                    2 * sum(y, x + 1) + sum(y + 1, x - 1) - 2 * sum(y + 1, x) + sum(y + 1, x + 1);
      response.push_back(std::abs(v));
    }
  if (response.empty()) return 0.0;
  auto mid = response.begin() + static_cast<std::ptrdiff_t>(response.size() / 2);
  std::nth_element(response.begin(), mid, response.end());
  // The mask's weights square-sum to 36, so its response to white noise has sigma 6 * sigma(sum of 3 channels);
  // the median of |N(0, s)| is 0.6745 s; and sigma(sum) = sqrt(3) * sigma(channel).
  return *mid / (0.6745 * 6.0) / std::sqrt(3.0);
}

cv::Mat normalise_photometric(const cv::Mat& bgr, const PhotometricConfig& config, PhotometricStats* stats) {
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
  cv::Mat out;
  if (s.black < 0.5 && s.gain <= 1.15) {
    out = input.clone();  // close enough to identity: keep the exact pixels
  } else {
    std::array<std::uint8_t, 256> curve{};
    for (int v = 0; v < 256; ++v)
      curve[static_cast<std::size_t>(v)] = cv::saturate_cast<std::uint8_t>(std::clamp((v - s.black) * s.gain, 0.0, 255.0));
    cv::LUT(input, cv::Mat(1, 256, CV_8U, curve.data()), out);
  }
  black_out_clipped(input, out, config.clip_level, s);
  if (stats) *stats = s;
  return out;
}

}  // namespace faultline::detector
