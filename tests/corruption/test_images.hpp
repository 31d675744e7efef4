// Small synthetic frames for the property tests: gradients, edges, texture; and degenerate frames.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

namespace faultline::testing {

inline cv::Mat scene(int rows, int cols, std::uint32_t salt = 1) {
  cv::Mat m(rows, cols, CV_8UC3);
  std::uint32_t s = 2463534242u ^ salt;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      s ^= s << 13, s ^= s >> 17, s ^= s << 5;  // xorshift texture
      const int edge = (x / 8 + y / 8) % 2 ? 60 : 0;
      m.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>((x * 255) / std::max(1, cols - 1)),
                    static_cast<uchar>((y * 200) / std::max(1, rows - 1) + (s & 31)),
                    static_cast<uchar>(std::min(255, edge + static_cast<int>(s % 150))));
    }
  }
  return m;
}

}  // namespace faultline::testing
