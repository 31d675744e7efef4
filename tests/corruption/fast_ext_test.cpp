// fast mode of the imagecorruptions / ISONoise pointwise corruptions against numpy mode on 1600x900
// frames: the noise corruptions within statistical tolerances (docs/faults.md), the deterministic
// ones exactly, Gaussian blur within one level on a bounded share of values.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "corruption/corrupt.hpp"
#include "corruption/test_images.hpp"

namespace faultline::corruption {
namespace {

const cv::Mat& frame_1600x900() {
  static const cv::Mat f = faultline::testing::scene(900, 1600, 77);
  return f;
}

cv::Mat numpy_out(const cv::Mat& in, Corruption c, int sev, std::uint32_t seed) {
  rng::NumpyRandomState rng(seed);
  return *corrupt(in, c, sev, rng);
}
cv::Mat fast_out(const cv::Mat& in, Corruption c, int sev, std::uint64_t seed) {
  rng::FastRng rng(seed);
  return *corrupt(in, c, sev, rng);
}

double psnr(const cv::Mat& a, const cv::Mat& b) {
  const double mse = cv::norm(a, b, cv::NORM_L2SQR) / static_cast<double>(a.total() * a.channels());
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

// Per-channel 256-bin histogram L1 distance over the value count, averaged over channels.
double hist_l1(const cv::Mat& a, const cv::Mat& b) {
  std::vector<double> ha(768, 0.0), hb(768, 0.0);
  const std::size_t n = a.total() * 3;
  for (std::size_t i = 0; i < n; ++i) {
    ha[(i % 3) * 256 + a.data[i]] += 1;
    hb[(i % 3) * 256 + b.data[i]] += 1;
  }
  double total = 0;
  for (std::size_t j = 0; j < 768; ++j) total += std::fabs(ha[j] - hb[j]);
  return total / static_cast<double>(n);
}

using NoiseParam = std::tuple<Corruption, int>;
class FastNoiseTest : public ::testing::TestWithParam<NoiseParam> {};

// Tolerances: mean and std within 0.3 levels, histogram L1 < 0.02, PSNR against the input within
// 0.3 dB, and per input level the mean output within 5 standard errors (the conditional-mean curve
// of each corruption).
TEST_P(FastNoiseTest, MatchesNumpyModeStatisticsOn1600x900) {
  const auto [type, sev] = GetParam();
  const cv::Mat& in = frame_1600x900();
  const cv::Mat a = numpy_out(in, type, sev, 40), b = fast_out(in, type, sev, 40);
  cv::Scalar ma, sa, mb, sb;
  cv::meanStdDev(a.reshape(1), ma, sa);
  cv::meanStdDev(b.reshape(1), mb, sb);
  EXPECT_NEAR(mb[0], ma[0], 0.3);
  EXPECT_NEAR(sb[0], sa[0], 0.3);
  EXPECT_LT(hist_l1(a, b), 0.02);
  EXPECT_NEAR(psnr(b, in), psnr(a, in), 0.3);
  std::vector<double> sum_a(256, 0), sum_b(256, 0), sq_a(256, 0), count(256, 0);
  for (std::size_t i = 0; i < in.total() * 3; ++i) {
    const int v = in.data[i];
    sum_a[v] += a.data[i];
    sq_a[v] += static_cast<double>(a.data[i]) * a.data[i];
    sum_b[v] += b.data[i];
    count[v] += 1;
  }
  int levels = 0;
  for (int v = 0; v < 256; ++v) {
    if (count[v] < 2000) continue;
    ++levels;
    const double mean_a = sum_a[v] / count[v], mean_b = sum_b[v] / count[v];
    const double sd = std::sqrt(std::max(sq_a[v] / count[v] - mean_a * mean_a, 0.25));
    EXPECT_NEAR(mean_b, mean_a, 5.0 * sd * std::sqrt(2.0 / count[v]) + 0.05) << "input level " << v;
  }
  EXPECT_GT(levels, 100);
}

INSTANTIATE_TEST_SUITE_P(
    Noises, FastNoiseTest,
    ::testing::Combine(::testing::Values(Corruption::GaussianNoise, Corruption::ShotNoise,
                                         Corruption::ImpulseNoise, Corruption::SpeckleNoise,
                                         Corruption::IsoNoise),
                       ::testing::Values(1, 3, 5)),
    [](const ::testing::TestParamInfo<NoiseParam>& p) {
      std::string name;
      bool up = true;
      for (char ch : std::string(to_string(std::get<0>(p.param)))) {
        if (ch == '_') {
          up = true;
          continue;
        }
        name += up ? static_cast<char>(std::toupper(static_cast<unsigned char>(ch))) : ch;
        up = false;
      }
      return name + "Sev" + std::to_string(std::get<1>(p.param));
    });

TEST(FastDeterministicTest, SharedImplementationsEqualNumpyModeOn1600x900) {
  const cv::Mat& in = frame_1600x900();
  for (Corruption c : {Corruption::Contrast, Corruption::Pixelate, Corruption::JpegCompression}) {
    for (int sev : {1, 3, 5}) {
      EXPECT_EQ(cv::norm(fast_out(in, c, sev, 1), numpy_out(in, c, sev, 1), cv::NORM_INF), 0.0)
          << to_string(c) << " sev " << sev;
    }
  }
}

// Fixed-point or closed-form paths against the float64 reference path: the truncation moves a value
// by one where the two straddle an integer. Bounds: max diff 1, on under 10 % of the values
// (saturate, whose severity 3, S x 2, makes every result an integer the reference's float path
// often lands just under; gaussian_blur, OpenCV's fixed-point blur of the dithered frame, whose
// rounding is one too high where frac(x) >= ~0.95: 2.6-7.7 % measured, its mean within 0.1).
TEST(FastDeterministicTest, SaturateAndGaussianBlurWithinOneLevelOn1600x900) {
  const cv::Mat& in = frame_1600x900();
  for (Corruption c : {Corruption::Saturate, Corruption::GaussianBlur}) {
    const double kMaxShare = 0.10;
    for (int sev = 1; sev <= 5; ++sev) {
      const cv::Mat a = numpy_out(in, c, sev, 1), b = fast_out(in, c, sev, 1);
      cv::Mat ne;
      cv::compare(a.reshape(1), b.reshape(1), ne, cv::CMP_NE);
      const double share = cv::countNonZero(ne) / static_cast<double>(ne.total());
      EXPECT_LE(cv::norm(a, b, cv::NORM_INF), 1.0) << to_string(c) << " sev " << sev;
      EXPECT_LT(share, kMaxShare) << to_string(c) << " sev " << sev;
      if (c == Corruption::GaussianBlur) {
        EXPECT_NEAR(cv::mean(b.reshape(1))[0], cv::mean(a.reshape(1))[0], 0.1) << "sev " << sev;
      }
      std::printf("%s sev %d: %.4f %% of values differ by 1\n", to_string(c), sev, 100 * share);
    }
  }
}

}  // namespace
}  // namespace faultline::corruption
