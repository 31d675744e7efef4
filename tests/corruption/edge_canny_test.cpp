// canny_l1 against cv::Canny (3 x 3 Sobel, L1 gradient) pixel for pixel, on its AVX2 and portable
// bodies: random, blob (spatter's liquid: zeros and ~170-200), stepped and smoothed images from
// 1 x 1 up, with the widths around the 16-pixel vector blocks.
#include "corruption/edge_canny.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/imgproc.hpp>

namespace faultline::corruption {
namespace {

cv::Mat make_image(int rows, int cols, int kind, std::uint32_t seed) {
  cv::Mat img(rows, cols, CV_8U);
  std::uint32_t s = seed * 2654435761u + 1;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      s = s * 1664525u + 1013904223u;
      const std::uint32_t v = s >> 24;
      std::uint8_t value = static_cast<std::uint8_t>(v);
      if (kind == 1) value = static_cast<std::uint8_t>(v < 160 ? 0 : 170 + v % 30);
      if (kind == 2) value = static_cast<std::uint8_t>((v % 8) * 30);
      if (kind == 3) value = static_cast<std::uint8_t>(v / 4);
      img.at<std::uint8_t>(y, x) = value;
    }
  }
  if (kind == 3) cv::GaussianBlur(img, img, cv::Size(5, 5), 1.0);
  if (kind == 1) cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  return img;
}

TEST(EdgeCannyTest, EqualsOpenCvCannyOnBothBodies) {
  const int sizes[][2] = {{1, 1},  {1, 7},   {2, 2},   {3, 3},   {5, 1},    {4, 15},
                          {9, 16}, {17, 17}, {31, 33}, {64, 47}, {120, 200}};
  int edges_seen = 0;
  for (const auto& size : sizes) {
    for (int kind = 0; kind < 4; ++kind) {
      const cv::Mat img = make_image(size[0], size[1], kind, static_cast<std::uint32_t>(kind + 7));
      cv::Mat expected;
      cv::Canny(img, expected, 50, 150);
      edges_seen += cv::countNonZero(expected);
      for (const bool simd : {true, false}) {
        const cv::Mat got = canny_l1(img, 50, 150, simd);
        ASSERT_EQ(got.size(), img.size());
        ASSERT_EQ(got.type(), CV_8U);
        EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0)
            << size[0] << "x" << size[1] << " kind " << kind << " simd " << simd;
      }
    }
  }
  EXPECT_GT(edges_seen, 1000);  // the images do have edges to find
}

// Weak pixels join an edge only through a chain to a strong one: a low ramp alone gives none.
TEST(EdgeCannyTest, WeakEdgesNeedAStrongNeighbour) {
  cv::Mat ramp(20, 20, CV_8U, cv::Scalar(0));
  ramp.colRange(10, 20).setTo(15);  // magnitude 60: weak only
  cv::Mat expected;
  cv::Canny(ramp, expected, 50, 150);
  EXPECT_EQ(cv::countNonZero(canny_l1(ramp, 50, 150)), 0);
  EXPECT_EQ(cv::countNonZero(expected), 0);
  ramp.rowRange(0, 5).colRange(10, 20).setTo(200);  // a strong stretch the weak one continues
  cv::Canny(ramp, expected, 50, 150);
  const cv::Mat got = canny_l1(ramp, 50, 150);
  EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::countNonZero(got.rowRange(10, 20)), 0);
}

}  // namespace
}  // namespace faultline::corruption
