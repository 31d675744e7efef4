// One entry point per RNG mode for the image corruptions. Pure: no I/O, no clocks, no globals.
// Input: CV_8UC3 in OpenCV's BGR order (what cv::imread returns), any size >= 1x1. Output: same
// size and type. Severity 0 is "off" and returns a copy without drawing; 1..5 follow the reference
// (spec corruptions.md).
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "common/status.hpp"
#include "corruption/types.hpp"
#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

struct CorruptOptions {
  std::optional<double>
      angle_deg;  // Motion Blur: use this angle (degrees) instead of drawing it; no draw then
  // Frost: textures (CV_8UC3 BGR, non-empty) to draw from instead of the five built-in ones; not
  // owned, must outlive the call. nullptr = built-in.
  const std::vector<cv::Mat>* frost_textures = nullptr;
  // Rolling Shutter: the ego yaw rate (rad/s, > 0 turning left) and the horizontal focal length
  // (pixels; <= 0: 0.8 x width). No yaw rate: the frame is returned unchanged (no motion to skew
  // by).
  std::optional<double> yaw_rate_rad_s;
  double focal_px = 0;
};

// numpy mode: bit-exact with the reference called right after np.random.seed(seed) when `rng` is a
// fresh NumpyRandomState(seed); consumes exactly the reference's draws.
Result<cv::Mat> corrupt(const cv::Mat& bgr, Corruption type, int severity,
                        rng::NumpyRandomState& rng, const CorruptOptions& options = {});

// (impulse_noise, which the reference cannot seed, runs the reference's algorithm on this stream
// instead.) fast mode: statistically equivalent; Bright, Color Quant, Contrast, Saturate, Pixelate,
// JPEG and angle-injected Motion Blur (up to float32 accumulation) equal numpy mode; Gaussian blur
// is float32 (within one level).
Result<cv::Mat> corrupt(const cv::Mat& bgr, Corruption type, int severity, rng::FastRng& rng,
                        const CorruptOptions& options = {});

// One call with a fresh RNG of `mode` seeded with `seed`: what `faultline corrupt --seed S --rng
// MODE` applies (numpy mode as after np.random.seed(seed)).
Result<cv::Mat> corrupt_seeded(const cv::Mat& bgr, Corruption type, int severity, RngMode mode,
                               std::uint32_t seed, const CorruptOptions& options = {});

// Checks the input image and severity; the error names what is wrong.
Status validate_input(const cv::Mat& bgr, int severity);

}  // namespace faultline::corruption
