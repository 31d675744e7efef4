// Lens soiling (Faultline's own): mud and dirt blobs stuck on the lens. The dirt sits far out of
// focus, so each blob is a soft, irregular, semi-opaque patch: where it covers the lens the camera
// sees the scene blurred (light scattered by the dirt) and tinted by the dirt's colour (light
// absorbed), blended by the dirt's opacity. The blobs are drawn once from the seed and stay fixed
// on the lens: only the scene behind them changes from frame to frame.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace faultline::corruption {

struct SoilingParams {
  int blobs;            // dirt blobs on the lens
  double coverage;      // share of the image area the blobs cover (before overlap)
  double opacity;       // peak opacity of a blob (0..1)
  double transmission;  // share of the light through the dirt that still reaches the sensor,
                        // scattered (0..1)
};
// Severity 1..5: light dust spots (2 blobs, 2 % of the area, opacity 0.45) up to a mud-caked lens
// (12 blobs, 30 %, opacity 0.97, 15 % transmission); docs/faults.md lists the table.
SoilingParams soiling_params(int severity);

// The dirt on one lens for one frame size: an opacity map drawn once.
class SoilingModel {
 public:
  SoilingModel(int severity, std::uint64_t seed, cv::Size size);

  // The soiled frame: out = I (1 - a) + a T, with T the scene blurred at 1/8 resolution, tinted by
  // the dirt and upsampled bilinearly. A black frame stays black (no light to scatter); CV_8UC3 of
  // the model's size.
  cv::Mat apply(const cv::Mat& bgr) const;

  const cv::Mat& alpha() const {
    return alpha_;
  }  // CV_8U opacity 0..255, fixed for the model's life
  cv::Size size() const { return alpha_.size(); }

 private:
  SoilingParams params_;
  cv::Mat alpha_;
  cv::Rect box_;                            // bounding box of alpha > 0 (may be empty)
  std::vector<std::pair<int, int>> spans_;  // per row: [first, last) column with alpha > 0
};

}  // namespace faultline::corruption
