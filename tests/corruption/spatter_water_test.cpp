// fast mode's water stages (spatter_water.hpp): the fused equalisation, emboss and 3 x 3 mean
// against OpenCV's calls, value for value, from 1 x 1 up; the liquid field's statistics.
#include "corruption/spatter_water.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

namespace faultline::corruption {
namespace {

// Values 0..20 as the capped edge distances: runs of 20 with dips towards 0 (edges), or a
// constant (equalizeHist's degenerate case).
cv::Mat distances(int rows, int cols, std::uint32_t seed, bool constant) {
  cv::Mat d(rows, cols, CV_8U);
  std::uint32_t s = seed * 2654435761u + 7;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      s = s * 1664525u + 1013904223u;
      const std::uint32_t v = s >> 27;  // 0..31
      d.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(constant ? 9 : (v > 20 ? 20 : v));
    }
  }
  return d;
}

TEST(SpatterWaterTest, EqualizeEmbossBlurEqualsOpenCv) {
  const int sizes[][2] = {{1, 1},  {1, 6},   {2, 2},   {3, 3},   {7, 1},
                          {5, 31}, {33, 32}, {40, 65}, {90, 160}};
  const cv::Mat_<int> emboss = (cv::Mat_<int>(3, 3) << -2, -1, 0, -1, 1, 1, 0, 1, 2);
  for (const auto& size : sizes) {
    for (const bool constant : {false, true}) {
      const cv::Mat in = distances(size[0], size[1], static_cast<std::uint32_t>(size[1]), constant);
      const cv::Mat liquid = distances(size[0], size[1], 99, false) * 12;  // 0..240
      cv::Mat expected;
      cv::equalizeHist(in, expected);
      cv::filter2D(expected, expected, CV_8U, emboss);
      cv::blur(expected, expected, cv::Size(3, 3));
      cv::Mat product;
      cv::multiply(liquid, expected, product, 1.0, CV_32S);
      double expected_max = 0;
      cv::minMaxLoc(product, nullptr, &expected_max);
      cv::Mat got = in.clone();
      const int max_product = equalize_emboss_blur(got, liquid);
      EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0)
          << size[0] << "x" << size[1] << (constant ? " constant" : "");
      EXPECT_EQ(max_product, static_cast<int>(expected_max)) << size[0] << "x" << size[1];
    }
  }
}

// The liquid: the same seed gives the same field; the fraction above the threshold is the normal
// field's, 1 - Phi((threshold - loc) / sd) with sd = scale sum w_k^2 (the separable taps), within
// 10 % (+ 0.002) of it on one 1600 x 900 frame (its sampling sd is ~0.001-0.003).
TEST(SpatterWaterTest, LiquidFractionIsTheNormalFieldsOne) {
  for (int severity = 1; severity <= 3; ++severity) {
    const SpatterParams p = spatter_params(severity);
    rng::FastRng a(21), b(21);
    WaterScratch sa, sb;
    water_liquid8(cv::Size(1600, 900), p, a, sa);
    water_liquid8(cv::Size(1600, 900), p, b, sb);
    ASSERT_EQ(cv::norm(sa.liquid8, sb.liquid8, cv::NORM_INF), 0.0);
    const int r = static_cast<int>(std::ceil(3 * p.sigma));
    double total = 0, squares = 0;
    for (int k = -r; k <= r; ++k) total += std::exp(-0.5 * k * k / (p.sigma * p.sigma));
    for (int k = -r; k <= r; ++k) {
      const double w = std::exp(-0.5 * k * k / (p.sigma * p.sigma)) / total;
      squares += w * w;
    }
    const double z = (p.threshold - p.loc) / (p.scale * squares);
    const double expected = 0.5 * std::erfc(z / std::sqrt(2.0));
    const double fraction = cv::countNonZero(sa.liquid8) / (1600.0 * 900.0);
    EXPECT_NEAR(fraction, expected, 0.1 * expected + 0.002) << "severity " << severity;
    // Liquid values are field * 255 at or above the threshold.
    double lo = 0, hi = 0;
    cv::minMaxLoc(sa.liquid8, nullptr, &hi);
    cv::Mat mask = sa.liquid8 > 0;
    cv::minMaxLoc(sa.liquid8, &lo, nullptr, nullptr, nullptr, mask);
    EXPECT_GE(lo, std::floor(p.threshold * 255) - 1) << "severity " << severity;
    EXPECT_LE(hi, 255.0);
  }
}

}  // namespace
}  // namespace faultline::corruption
