// rolling_shutter: a per-row horizontal shift with linear interpolation (fixed point, 8 fractional
// bits).
#include "corruption/rolling_shutter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace faultline::corruption {

double rolling_shutter_readout_ms(int severity) {
  static constexpr double kMs[] = {5, 10, 20, 33, 50};
  return kMs[static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1)];
}

double default_focal_px(int width) { return 0.8 * width; }

cv::Mat rolling_shutter(const cv::Mat& bgr, int severity, double yaw_rate_rad_s, double focal_px) {
  if (focal_px <= 0 || !std::isfinite(focal_px)) focal_px = default_focal_px(bgr.cols);
  if (!std::isfinite(yaw_rate_rad_s)) yaw_rate_rad_s = 0;
  const double readout_s = rolling_shutter_readout_ms(severity) * 1e-3;
  cv::Mat out(bgr.size(), CV_8UC3);
  const int w = bgr.cols;
  for (int y = 0; y < bgr.rows; ++y) {
    const double phase = bgr.rows > 1 ? static_cast<double>(y) / (bgr.rows - 1) - 0.5 : 0.0;
    // Clamped to the frame width: beyond it every pixel is the replicated edge anyway.
    const double dx =
        std::clamp(focal_px * std::tan(yaw_rate_rad_s * readout_s * phase), -1.0 * w, 1.0 * w);
    const double fl = std::floor(dx);
    const int shift = static_cast<int>(fl);
    const int frac = static_cast<int>(
        std::lround((dx - fl) * 256.0));  // weight of the left neighbour's left one
    const auto* src = bgr.ptr<cv::Vec3b>(y);
    auto* dst = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < w; ++x) {
      // out(x) = in(x - dx) = (1 - f) in(x - shift) + f in(x - shift - 1).
      const int a = std::clamp(x - shift, 0, w - 1), b = std::clamp(x - shift - 1, 0, w - 1);
      for (int c = 0; c < 3; ++c) {
        dst[x][c] =
            static_cast<std::uint8_t>(((256 - frac) * src[a][c] + frac * src[b][c] + 128) >> 8);
      }
    }
  }
  return out;
}

}  // namespace faultline::corruption
