// Exposure flicker: one gain per row in 16.16 fixed point, applied with integer multiplies.
#include "corruption/exposure_flicker.hpp"

#include <algorithm>
#include <cmath>

#include "rng/fast_rng.hpp"

namespace faultline::corruption {
namespace {

constexpr double kGamma = 2.2;
constexpr double kTwoPi = 2.0 * M_PI;

}  // namespace

ExposureFlickerParams exposure_flicker_params(int severity) {
  static const ExposureFlickerParams kTable[] = {
      {0.1, 0.1, 0.0}, {0.2, 0.25, 0.0}, {0.3, 0.45, 0.05}, {0.45, 0.7, 0.10}, {0.6, 1.0, 0.20}};
  return kTable[std::clamp(severity, 1, 5) - 1];
}

ExposureFlickerModel::ExposureFlickerModel(int severity, std::uint64_t seed)
    : params_(exposure_flicker_params(severity)) {
  rng::FastRng rng(seed);
  flicker_hz_ = rng.uniform(2.0, 5.5);
  flicker_phase_ = rng.uniform(0, kTwoPi);
  hunt_hz_ = rng.uniform(0.3, 0.8);
  hunt_phase_ = rng.uniform(0, kTwoPi);
  envelope_hz_ = rng.uniform(0.03, 0.08);
  envelope_phase_ = rng.uniform(0, kTwoPi);
  bands_per_frame_ = rng.uniform(2.0, 6.0);
  band_phase_ = rng.uniform(0, kTwoPi);
}

double ExposureFlickerModel::exposure_ev(double time_s) const {
  // Reduce the phase first: capture stamps since the epoch (~1e9 s) keep their sub-millisecond
  // resolution.
  auto wave = [&](double hz, double phase) {
    return std::sin(kTwoPi * std::fmod(hz * time_s, 1.0) + phase);
  };
  const double envelope = 0.5 + 0.5 * wave(envelope_hz_, envelope_phase_);
  return params_.flicker_ev * wave(flicker_hz_, flicker_phase_) +
         params_.hunting_ev * envelope * wave(hunt_hz_, hunt_phase_);
}

double ExposureFlickerModel::band_gain(int y, int rows, double time_s) const {
  if (params_.band_depth <= 0) return 1.0;
  // The bands drift down the frame with the flicker's beat.
  const double cycles =
      bands_per_frame_ * (y + 0.5) / std::max(1, rows) - std::fmod(flicker_hz_ * time_s, 1.0);
  return 1.0 + params_.band_depth * std::sin(kTwoPi * cycles + band_phase_);
}

cv::Mat ExposureFlickerModel::apply(const cv::Mat& bgr, double time_s) const {
  cv::Mat out(bgr.size(), bgr.type());
  const double frame_gain = std::pow(2.0, exposure_ev(time_s));
  const int n = bgr.cols * 3;
  for (int y = 0; y < bgr.rows; ++y) {
    const double g = std::pow(frame_gain * band_gain(y, bgr.rows, time_s), 1.0 / kGamma);
    const auto g16 = static_cast<std::uint32_t>(std::lround(std::min(g, 255.0) * 65536.0));
    const uchar* s = bgr.ptr<uchar>(y);
    uchar* o = out.ptr<uchar>(y);
    for (int i = 0; i < n; ++i)
      o[i] = static_cast<uchar>(std::min<std::uint32_t>(255u, (s[i] * g16 + 32768u) >> 16));
  }
  return out;
}

}  // namespace faultline::corruption
