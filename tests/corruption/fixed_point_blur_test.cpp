// The fixed-point blur: its kernel, its arithmetic (held to a plain restatement of the documented
// sums, so the vector path and the portable one, run by the scalar.* suites, give the same bytes),
// flat frames, and its distance from the float64 Gaussian.
#include "corruption/fixed_point_blur.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "corruption/ndimage.hpp"

namespace faultline::corruption {
namespace {

// The documented sums, one value at a time: column pass in Q15 rounded to Q6, row pass, floor (and
// flat[v] where the sum is within 1/512 of a level above v).
cv::Mat restated_blur(const cv::Mat& in, const FixedPointKernel& k,
                      const std::array<std::uint8_t, 256>* flat = nullptr) {
  const int r = k.radius, rows = in.rows, cols = in.cols, ch = in.channels();
  cv::Mat mid(rows, cols, CV_32SC(ch)), out(in.size(), in.type());
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols * ch; ++x) {
      long long s = 0;
      for (int t = -r; t <= r; ++t) {
        s += k.weight[static_cast<std::size_t>(std::abs(t))] *
             in.ptr<std::uint8_t>(std::clamp(y + t, 0, rows - 1))[x];
      }
      mid.ptr<std::int32_t>(y)[x] = static_cast<std::int32_t>((s + 256) >> 9);
    }
  }
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      for (int c = 0; c < ch; ++c) {
        long long s = 0;
        for (int t = -r; t <= r; ++t) {
          s += k.weight[static_cast<std::size_t>(std::abs(t))] *
               mid.ptr<std::int32_t>(y)[std::clamp(x + t, 0, cols - 1) * ch + c];
        }
        auto v = static_cast<std::uint8_t>(std::min(s >> 21, 255LL));
        if (flat && (s & ((1 << 21) - 1)) < (1 << 12)) v = (*flat)[v];
        out.ptr<std::uint8_t>(y)[x * ch + c] = v;
      }
    }
  }
  return out;
}

cv::Mat random_frame(int rows, int cols, int type, int seed) {
  cv::Mat m(rows, cols, type);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  return m;
}

TEST(FixedPointBlurTest, KernelWeightsSumToOneExactlyAndFollowTheGaussian) {
  for (const double sigma : {0.7, 1.0, 1.5, 2.0, 6.0}) {
    const int r = nd::gaussian_radius(sigma, 4.0);
    const FixedPointKernel k = fixed_point_gaussian(sigma, r);
    const std::vector<double> w = nd::gaussian_kernel(sigma, r);
    ASSERT_EQ(k.radius, r);
    int sum = k.weight[0];
    for (int t = 1; t <= r; ++t) sum += 2 * k.weight[static_cast<std::size_t>(t)];
    EXPECT_EQ(sum, 1 << 15) << sigma;
    for (int t = 0; t <= r; ++t) {
      EXPECT_NEAR(k.weight[static_cast<std::size_t>(t)] / 32768.0, w[static_cast<std::size_t>(t)],
                  t == 0 ? 2 * r / 32768.0 : 0.5 / 32768.0)
          << sigma << " tap " << t;
    }
  }
  EXPECT_THROW(fixed_point_kernel({}), std::invalid_argument);
  EXPECT_THROW(fixed_point_kernel({0.2, 0.6}), std::invalid_argument);  // centre below 0
  EXPECT_THROW(fixed_point_kernel({1.0}), std::invalid_argument);       // centre 1
}

TEST(FixedPointBlurTest, EqualsTheDocumentedSumsOnRandomFrames) {
  // Widths around the 16-value vector blocks, one and three channels, several radii.
  for (const int cols : {1, 5, 6, 17, 37}) {
    for (const int type : {CV_8UC1, CV_8UC3}) {
      for (const double sigma : {0.6, 1.0, 2.0, 3.5}) {
        const cv::Mat in = random_frame(23, cols, type, cols * 10 + type);
        const FixedPointKernel k = fixed_point_gaussian(sigma, nd::gaussian_radius(sigma, 4.0));
        cv::Mat out;
        fixed_point_blur(in, k, out);
        EXPECT_EQ(cv::norm(out, restated_blur(in, k), cv::NORM_INF), 0.0)
            << cols << " cols, type " << type << ", sigma " << sigma;
      }
    }
  }
}

// Frames with flat patches (whose sums land on their levels) and noise, so that blocks of 16 values
// mix values that take the table and values that do not.
TEST(FixedPointBlurTest, TakesTheFlatTableWhereTheSumLandsOnALevel) {
  std::array<std::uint8_t, 256> halves{};
  for (std::size_t v = 0; v < 256; ++v) halves[v] = static_cast<std::uint8_t>(v / 2);
  for (const int cols : {7, 40}) {
    cv::Mat in = random_frame(30, cols, CV_8UC3, cols);
    in(cv::Rect(1, 2, cols / 2, 20)).setTo(cv::Scalar(90, 91, 92));
    const FixedPointKernel k = fixed_point_gaussian(1.0, 4);
    cv::Mat out;
    fixed_point_blur(in, k, out, &halves);
    EXPECT_EQ(cv::norm(out, restated_blur(in, k, &halves), cv::NORM_INF), 0.0) << cols;
    // Inside the patch, beyond the kernel's reach of its edges, every value is its level's entry.
    if (cols == 40) {
      const cv::Mat inner = out(cv::Rect(6, 7, cols / 2 - 10, 10)).clone();
      EXPECT_EQ(
          cv::norm(inner, cv::Mat(inner.size(), CV_8UC3, cv::Scalar(45, 45, 46)), cv::NORM_INF),
          0.0);
    }
  }
}

TEST(FixedPointBlurTest, FlatFramesKeepTheirValue) {
  const FixedPointKernel k = fixed_point_gaussian(2.0, 8);
  for (const int v : {0, 1, 17, 128, 254, 255}) {
    for (const cv::Size size : {cv::Size(1, 1), cv::Size(3, 2), cv::Size(64, 40)}) {
      const cv::Mat in(size, CV_8UC3, cv::Scalar(v, v, v));
      cv::Mat out;
      fixed_point_blur(in, k, out);
      EXPECT_EQ(cv::norm(out, in, cv::NORM_INF), 0.0) << v << " at " << size;
    }
  }
}

TEST(FixedPointBlurTest, IsTheFloorOfTheGaussianWithinALevel) {
  const cv::Mat in = random_frame(120, 200, CV_8UC3, 7);
  cv::Mat smooth;
  cv::blur(in, smooth, cv::Size(3, 3));  // some structure besides noise
  const double sigma = 1.5;
  const int r = nd::gaussian_radius(sigma, 4.0);
  cv::Mat exact;
  smooth.convertTo(exact, CV_64FC3);
  nd::gaussian_filter(exact, sigma, sigma, nd::Extend::Nearest);
  cv::Mat floor8(smooth.size(), CV_8UC3);
  for (int y = 0; y < exact.rows; ++y) {
    for (int x = 0; x < exact.cols * 3; ++x) {
      floor8.ptr<std::uint8_t>(y)[x] =
          static_cast<std::uint8_t>(std::floor(exact.ptr<double>(y)[x]));
    }
  }
  cv::Mat out;
  fixed_point_blur(smooth, fixed_point_gaussian(sigma, r), out);
  cv::Mat ne;
  cv::compare(out.reshape(1), floor8.reshape(1), ne, cv::CMP_NE);
  EXPECT_LE(cv::norm(out, floor8, cv::NORM_INF), 1.0);
  EXPECT_LT(cv::countNonZero(ne), static_cast<int>(0.02 * static_cast<double>(ne.total())));
}

TEST(FixedPointBlurTest, AnOutputThatIsTheInputGetsTheSameResult) {
  const cv::Mat in = random_frame(31, 45, CV_8UC3, 3);
  const FixedPointKernel k = fixed_point_gaussian(1.0, 4);
  cv::Mat separate, same = in.clone();
  fixed_point_blur(in, k, separate);
  fixed_point_blur(same, k, same);
  EXPECT_EQ(cv::norm(same, separate, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace faultline::corruption
