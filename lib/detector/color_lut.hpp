// Pixel -> detection class for the synthetic renderer's palette. A body colour is shaded by a
// scalar factor (0.40..0.95, synth_palette.hpp), so a pixel belongs to a class when its BGR
// direction is within a small angle of the class colour (shading-invariant) and its brightness
// factor is plausible. Looked up through a 32^3 table.
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>

namespace faultline::detector {

constexpr std::uint8_t kNoClass = 255;

struct ColorLutConfig {
  double max_angle_deg =
      11.0;  // palette colours are >= 13.7 deg apart, scenery >= 29 deg from any class
  double min_shade = 0.22;  // darker than this fraction of the body colour = not an object pixel
  double max_shade = 1.12;
  int min_max_channel = 28;  // near-black pixels have no reliable hue
};

class ColorLut {
 public:
  explicit ColorLut(const ColorLutConfig& config = {});
  // Class index (dataset::SynthClass order) or kNoClass.
  std::uint8_t classify(std::uint8_t b, std::uint8_t g, std::uint8_t r) const {
    return table_[(static_cast<unsigned>(b >> 3) << 10) | (static_cast<unsigned>(g >> 3) << 5) |
                  (r >> 3)];
  }
  // Exact (unquantised) decision, used to build the table.
  static std::uint8_t classify_exact(double b, double g, double r, const ColorLutConfig& config);
  // CV_8UC3 BGR -> CV_8UC1 class labels.
  cv::Mat label_image(const cv::Mat& bgr) const;
  // The same into `labels`, whose buffer is reused when it has the right size.
  void label_image(const cv::Mat& bgr, cv::Mat& labels) const;

 private:
  std::array<std::uint8_t, 32 * 32 * 32> table_{};
};

}  // namespace faultline::detector
