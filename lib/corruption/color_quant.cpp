// Color quant as a bitwise AND (vectorised by OpenCV).
#include "corruption/color_quant.hpp"

#include <algorithm>

namespace faultline::corruption {

int color_quant_mask(int severity) {
  const int bits = 5 - std::clamp(severity, 1, 5);
  return (0xFF << (8 - bits)) & 0xFF;
}

cv::Mat color_quant(const cv::Mat& img, int severity) {
  cv::Mat out;
  const int m = color_quant_mask(severity);
  cv::bitwise_and(img, cv::Scalar::all(m), out);
  return out;
}

}  // namespace faultline::corruption
