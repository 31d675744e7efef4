// fast mode of defocus_blur, zoom_blur, glass_blur, frost, elastic_transform and spatter against
// numpy mode (the reference's arithmetic, held to the goldens by golden_ext_spatial_test) on
// 1600x900 frames. Defocus: close to numpy mode value for value; zoom: close in PSNR and mean.
// Random ones: as close
// to a numpy-mode output as another numpy-mode seed is (PSNR within a margin of the seed-to-seed
// PSNR, histogram and mean), measured here on the same frame.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "corruption/corrupt.hpp"
#include "corruption/frost.hpp"
#include "corruption/glass_blur.hpp"
#include "corruption/test_images.hpp"

namespace faultline::corruption {
namespace {

// A 1600x900 frame with large smooth areas, edges and fine texture (the scene's noise softened).
const cv::Mat& frame_1600x900() {
  static const cv::Mat frame = [] {
    cv::Mat f = faultline::testing::scene(900, 1600);
    cv::GaussianBlur(f, f, cv::Size(), 1.5);
    cv::rectangle(f, cv::Rect(200, 150, 500, 300), cv::Scalar(40, 90, 200), cv::FILLED);
    cv::rectangle(f, cv::Rect(900, 500, 400, 250), cv::Scalar(230, 230, 230), cv::FILLED);
    cv::circle(f, cv::Point(1200, 250), 120, cv::Scalar(10, 10, 10), cv::FILLED);
    return f;
  }();
  return frame;
}

cv::Mat numpy_out(Corruption c, int sev, std::uint32_t seed) {
  rng::NumpyRandomState rng(seed);
  return *corrupt(frame_1600x900(), c, sev, rng);
}

cv::Mat fast_out(Corruption c, int sev, std::uint64_t seed) {
  rng::FastRng rng(seed);
  return *corrupt(frame_1600x900(), c, sev, rng);
}

double psnr(const cv::Mat& a, const cv::Mat& b) {
  const double mse = cv::norm(a, b, cv::NORM_L2SQR) / static_cast<double>(a.total() * a.channels());
  return mse == 0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

double mean_of(const cv::Mat& m) { return cv::mean(m.reshape(1))[0]; }

double hist_l1(const cv::Mat& a, const cv::Mat& b) {
  double total = 0;
  for (int c = 0; c < 3; ++c) {
    std::vector<double> ha(256), hb(256);
    for (int y = 0; y < a.rows; ++y) {
      for (int x = 0; x < a.cols; ++x) {
        ha[a.at<cv::Vec3b>(y, x)[c]] += 1;
        hb[b.at<cv::Vec3b>(y, x)[c]] += 1;
      }
    }
    for (std::size_t v = 0; v < 256; ++v) total += std::fabs(ha[v] - hb[v]);
  }
  return total / 3.0 / static_cast<double>(a.total());
}

double fraction_different(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::compare(a.reshape(1), b.reshape(1), d, cv::CMP_NE);
  return cv::countNonZero(d) / static_cast<double>(d.total());
}

using Case = std::tuple<Corruption, int>;

class FastDeterministicTest : public ::testing::TestWithParam<Case> {};

// Defocus: the disk's sums in exact integers (moved down a row at a time), the anti-aliasing
// Gaussian after it in float32, and at severities 4 and 5 three taps per side for the rim the
// reference's grid folds back in (a value differs where the float64 sum truncates the other way).
TEST_P(FastDeterministicTest, CloseToNumpyModeValueForValue) {
  const auto [c, sev] = GetParam();
  const cv::Mat ref = numpy_out(c, sev, 0), out = fast_out(c, sev, 0);
  EXPECT_LE(cv::norm(out, ref, cv::NORM_INF), 1.0);
  EXPECT_LT(fraction_different(out, ref), 0.01);
  EXPECT_NEAR(mean_of(out), mean_of(ref), 0.1);
}

INSTANTIATE_TEST_SUITE_P(Blurs, FastDeterministicTest,
                         ::testing::Combine(::testing::Values(Corruption::DefocusBlur),
                                            ::testing::Values(1, 2, 3, 4, 5)));

class FastZoomTest : public ::testing::TestWithParam<int> {};

// Zoom: 16 layers from four cascaded zooms (every product of a subset of four fitted factors)
// instead of the reference's 12-17 single zooms, as four 8-bit means of two images. The layers'
// scales follow the reference's within about 1 % of scale, but each cascaded zoom resamples again
// and the crops' half-pixel offsets add up: values move by tens of levels at high-contrast edges
// far from the centre, and the bulk stays close (PSNR and mean bounds measured on this frame with
// margin: 37.2-42.0 dB, mean 0.02 below to 0.05 above (OpenCV's resize and rounded 8-bit layers
// were 0.07-0.14 below), mean abs diff up to 1.8).
TEST_P(FastZoomTest, CloseToNumpyModeInPsnrAndMean) {
  const int sev = GetParam();
  const cv::Mat ref = numpy_out(Corruption::ZoomBlur, sev, 0);
  const cv::Mat out = fast_out(Corruption::ZoomBlur, sev, 0);
  EXPECT_GT(psnr(out, ref), 35.0);
  EXPECT_NEAR(mean_of(out), mean_of(ref), 0.25);
  cv::Mat diff;
  cv::absdiff(out, ref, diff);
  EXPECT_LT(mean_of(diff), 2.5);  // 1.5-1.8 measured at severities 3-5
  // Blurred, not sharp: the fast output is much closer to the reference than the input is.
  EXPECT_GT(psnr(out, ref), psnr(frame_1600x900(), ref) + 8.0);
}

INSTANTIATE_TEST_SUITE_P(Severities, FastZoomTest, ::testing::Values(1, 2, 3, 4, 5));

class FastRandomTest : public ::testing::TestWithParam<Case> {};

TEST_P(FastRandomTest, AsCloseToNumpyModeAsAnotherSeedIs) {
  const auto [c, sev] = GetParam();
  const cv::Mat a = numpy_out(c, sev, 11), b = numpy_out(c, sev, 12), f = fast_out(c, sev, 13);
  const double seed_psnr = psnr(b, a), seed_hist = hist_l1(b, a);
  EXPECT_NEAR(psnr(f, a), seed_psnr, 0.75) << "seed-to-seed PSNR " << seed_psnr;
  EXPECT_LE(hist_l1(f, a), 2.0 * seed_hist + 0.01) << "seed-to-seed histogram L1 " << seed_hist;
  EXPECT_NEAR(mean_of(f), mean_of(a), std::fabs(mean_of(b) - mean_of(a)) + 0.5);
}

INSTANTIATE_TEST_SUITE_P(Random, FastRandomTest,
                         ::testing::Combine(::testing::Values(Corruption::GlassBlur,
                                                              Corruption::ElasticTransform,
                                                              Corruption::Spatter),
                                            ::testing::Values(2, 5)));

// glass_blur's walk offsets: the AVX2 and portable bodies give the same values, every (dx, dy) in
// [-d, d)^2 and equally likely (chi-square over 50 rows of 1 592 pixels, alpha 0.001).
TEST(FastGlassTest, WalkOffsetsAreTheSameOnEveryPathAndUniform) {
  constexpr std::size_t kCount = 1592;
  constexpr std::int32_t kRowStep = 4800;
  static constexpr double kChi2Limit[] = {16.27, 37.70, 66.62, 103.4};  // 4 d^2 - 1 dof
  for (int d = 1; d <= 4; ++d) {
    rng::FastRng seed(100 + static_cast<std::uint64_t>(d));
    rng::LaneRng vector_lanes(seed);
    rng::LaneRng portable_lanes = vector_lanes;
    std::vector<std::int32_t> a((kCount + 15) / 16 * 16), b(a.size());
    std::vector<double> counts(static_cast<std::size_t>(4 * d * d), 0.0);
    const int rows = 50;
    for (int row = 0; row < rows; ++row) {
      detail::glass_row_offsets(a.data(), kCount, vector_lanes, d, kRowStep, true);
      detail::glass_row_offsets(b.data(), kCount, portable_lanes, d, kRowStep, false);
      ASSERT_EQ(a, b) << "d " << d << " row " << row;
      for (std::size_t k = 0; k < kCount; ++k) {
        const auto dy = static_cast<int>(std::lround(a[k] / static_cast<double>(kRowStep)));
        const int dx3 = a[k] - dy * kRowStep;
        ASSERT_EQ(dx3 % 3, 0);
        const int dx = dx3 / 3;
        ASSERT_TRUE(dx >= -d && dx < d && dy >= -d && dy < d) << dx << ", " << dy;
        counts[static_cast<std::size_t>((dy + d) * 2 * d + dx + d)] += 1;
      }
    }
    const double expected = rows * static_cast<double>(kCount) / static_cast<double>(counts.size());
    double chi2 = 0;
    for (const double c : counts) chi2 += (c - expected) * (c - expected) / expected;
    EXPECT_LT(chi2, kChi2Limit[d - 1]) << "d " << d;
  }
}

// Frost's blend is numpy mode's code; fast mode only draws the texture and the crop with FastRng.
TEST(FastFrostTest, IsTheReferenceBlendOfItsOwnDraws) {
  const cv::Mat& in = frame_1600x900();
  for (int sev = 1; sev <= 5; ++sev) {
    rng::FastRng rng(40 + static_cast<std::uint64_t>(sev)), copy = rng;
    const cv::Mat out = *corrupt(in, Corruption::Frost, sev, rng);
    const auto index = copy.bounded(5);
    const cv::Mat rescaled = frost_rescale(builtin_frost_textures()[index], in.rows, in.cols);
    const int y0 =
        static_cast<int>(copy.bounded(static_cast<std::uint32_t>(rescaled.rows - in.rows)));
    const int x0 =
        static_cast<int>(copy.bounded(static_cast<std::uint32_t>(rescaled.cols - in.cols)));
    EXPECT_EQ(cv::norm(out, frost_blend(in, rescaled, y0, x0, sev), cv::NORM_INF), 0.0) << sev;
  }
}

// The texture choice is uniform over the five (chi-square, 4 degrees of freedom, alpha
// 0.001: 18.47).
TEST(FastFrostTest, TextureChoiceIsUniform) {
  rng::FastRng rng(3);
  std::vector<double> counts(5, 0.0);
  const int n = 5000;
  for (int i = 0; i < n; ++i) counts[rng.bounded(5)] += 1;
  double chi2 = 0;
  for (const double k : counts) chi2 += (k - n / 5.0) * (k - n / 5.0) / (n / 5.0);
  EXPECT_LT(chi2, 18.47);
}

}  // namespace
}  // namespace faultline::corruption
