// Degenerate frames for every corruption: tiny, odd-sized and constant frames keep their shape,
// and what each imagecorruptions / ISONoise corruption defines on flat frames (split from
// property_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "corruption/brightness.hpp"
#include "corruption/color_quant.hpp"
#include "corruption/corrupt.hpp"
#include "corruption/dark.hpp"
#include "corruption/fog.hpp"
#include "corruption/frost.hpp"
#include "corruption/noise.hpp"
#include "corruption/run_corruption.hpp"
#include "corruption/spatter.hpp"
#include "corruption/test_images.hpp"

namespace faultline::corruption {
namespace {

// Degenerate frames: tiny, odd-sized, smaller than any blur kernel, constant, all black, all white.
class DegenerateFrameTest : public ::testing::TestWithParam<std::tuple<Corruption, RngMode>> {};

TEST_P(DegenerateFrameTest, EverySeverityWorksOnTinyAndConstantFrames) {
  const auto [type, mode] = GetParam();
  const cv::Mat frames[] = {faultline::testing::scene(1, 1),
                            faultline::testing::scene(2, 2),
                            faultline::testing::scene(2, 3),
                            faultline::testing::scene(7, 5),
                            faultline::testing::scene(40, 3),
                            cv::Mat(20, 30, CV_8UC3, cv::Scalar::all(0)),
                            cv::Mat(20, 30, CV_8UC3, cv::Scalar::all(255)),
                            cv::Mat(9, 11, CV_8UC3, cv::Scalar(80, 120, 160))};
  for (const cv::Mat& f : frames) {
    for (int sev = 1; sev <= 5; ++sev) {
      const cv::Mat out = run(f, type, sev, mode, 21);
      ASSERT_EQ(out.size(), f.size())
          << to_string(type) << " sev " << sev << " " << f.rows << "x" << f.cols;
      ASSERT_EQ(out.type(), CV_8UC3);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllTypes, DegenerateFrameTest,
                         ::testing::Combine(::testing::ValuesIn(kAllCorruptions),
                                            ::testing::Values(RngMode::Numpy, RngMode::Fast)));

// The imagecorruptions / ISONoise corruptions on flat frames, in both modes: what each defines
// there.
TEST(DegenerateBehaviourTest, PointwiseCorruptionsOnFlatFrames) {
  const cv::Mat black(24, 36, CV_8UC3, cv::Scalar::all(0)),
      white(24, 36, CV_8UC3, cv::Scalar::all(255));
  const cv::Mat flat(24, 36, CV_8UC3, cv::Scalar(80, 120, 160));
  for (const RngMode mode : {RngMode::Numpy, RngMode::Fast}) {
    for (int sev = 1; sev <= 5; ++sev) {
      const std::string at = std::string(to_string(mode)) + " sev " + std::to_string(sev);
      auto mean_of = [&](const cv::Mat& in, Corruption c) {
        return cv::mean(run(in, c, sev, mode, 9).reshape(1))[0];
      };
      auto max_diff = [&](const cv::Mat& in, Corruption c) {
        return cv::norm(run(in, c, sev, mode, 9), in, cv::NORM_INF);
      };
      // Multiplicative or photon noise on black has nothing to act on; additive noise clipped at 0
      // brightens it.
      EXPECT_EQ(max_diff(black, Corruption::SpeckleNoise), 0.0) << at;
      EXPECT_EQ(max_diff(black, Corruption::ShotNoise), 0.0) << at;
      EXPECT_GT(mean_of(black, Corruption::GaussianNoise), 1.0) << at;
      EXPECT_GT(mean_of(black, Corruption::IsoNoise), 1.0) << at;
      // White: photon noise stays near white (k / c clipped at 1), additive noise darkens it.
      EXPECT_GT(mean_of(white, Corruption::ShotNoise), 150.0) << at;
      EXPECT_LT(mean_of(white, Corruption::GaussianNoise), 254.0) << at;
      // The deterministic ones keep flat frames flat (the blur up to the reference's truncation of
      // float noise).
      for (const cv::Mat* in : {&black, &white, &flat}) {
        EXPECT_EQ(max_diff(*in, Corruption::Pixelate), 0.0) << at;
        EXPECT_LE(max_diff(*in, Corruption::Contrast), 1.0) << at;
        EXPECT_LE(max_diff(*in, Corruption::GaussianBlur), 1.0) << at;
        // JPEG keeps a flat frame flat, its colour moved by the quantised chroma at most.
        const cv::Mat jpeg = run(*in, Corruption::JpegCompression, sev, mode, 9);
        cv::Scalar jm, jsd;
        cv::meanStdDev(jpeg, jm, jsd);
        EXPECT_EQ(jsd, cv::Scalar::all(0)) << at;
        EXPECT_LE(cv::norm(jpeg, *in, cv::NORM_INF), 10.0) << at;
      }
      EXPECT_EQ(max_diff(black, Corruption::Saturate), 0.0) << at;
      // Grey has S = 0 and hue 0 (channel 0): an offset b > 0 (severities 4, 5) tints it towards
      // channel 0, as the reference does: (255, 255 (1 - b), 255 (1 - b)) truncated.
      const cv::Vec3b w = run(white, Corruption::Saturate, sev, mode, 9).at<cv::Vec3b>(3, 4);
      const int tint = sev == 4 ? 229 : (sev == 5 ? 204 : 255);
      EXPECT_EQ(w, cv::Vec3b(255, static_cast<uchar>(tint), static_cast<uchar>(tint))) << at;
    }
  }
}

TEST(DegenerateBehaviourTest, ImpulseNoiseOnGreyOnlyAddsSaltAndPepper) {
  const cv::Mat grey(50, 60, CV_8UC3, cv::Scalar::all(128));
  for (const RngMode mode : {RngMode::Numpy, RngMode::Fast}) {
    const cv::Mat out = run(grey, Corruption::ImpulseNoise, 5, mode, 3);
    cv::Mat kept, salt, pepper;
    cv::compare(out.reshape(1), 128, kept, cv::CMP_EQ);
    cv::compare(out.reshape(1), 255, salt, cv::CMP_EQ);
    cv::compare(out.reshape(1), 0, pepper, cv::CMP_EQ);
    const int n = static_cast<int>(out.total() * 3);
    EXPECT_EQ(cv::countNonZero(kept) + cv::countNonZero(salt) + cv::countNonZero(pepper), n);
    // amount 0.27, half salt: 9000 values, so each share within a few percent.
    EXPECT_NEAR(cv::countNonZero(salt) / static_cast<double>(n), 0.135, 0.02);
    EXPECT_NEAR(cv::countNonZero(pepper) / static_cast<double>(n), 0.135, 0.02);
  }
}

TEST(DegenerateBehaviourTest, DarkOnConstantFrameIsPureReadNoise) {
  for (const int v : {0, 128, 255}) {
    const cv::Mat flat(40, 50, CV_8UC3, cv::Scalar::all(v));
    rng::NumpyRandomState rng(4);
    auto out = corrupt(flat, Corruption::Dark, 4, rng);
    ASSERT_TRUE(out.is_ok());
    // trunc(255 * max(0, N(0, 0.038))): mean about 3.6 (spec §3), never large.
    const double mean = cv::mean(out->reshape(1))[0];
    EXPECT_GT(mean, 2.0);
    EXPECT_LT(mean, 6.0);
  }
}

TEST(DegenerateBehaviourTest, DarkSeverityFiveIsDarkerThanFour) {
  const cv::Mat in = faultline::testing::scene(64, 96);
  rng::NumpyRandomState a(1), b(1);
  const double m4 = cv::mean(corrupt(in, Corruption::Dark, 4, a)->reshape(1))[0];
  const double m5 = cv::mean(corrupt(in, Corruption::Dark, 5, b)->reshape(1))[0];
  EXPECT_LT(m5, m4);
}

TEST(DegenerateBehaviourTest, BrightnessTurnsBlackIntoGreyAndKeepsWhite) {
  rng::NumpyRandomState rng(0);
  auto black = corrupt(cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(0)), Corruption::Brightness, 5, rng);
  auto white =
      corrupt(cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(255)), Corruption::Brightness, 5, rng);
  EXPECT_EQ(black->at<cv::Vec3b>(0, 0), cv::Vec3b(127, 127, 127));
  EXPECT_EQ(white->at<cv::Vec3b>(3, 3), cv::Vec3b(255, 255, 255));
}

TEST(DegenerateBehaviourTest, FastMotionBlurKeepsTinyImagesBrightness) {
  const cv::Mat one(1, 1, CV_8UC3, cv::Scalar(10, 100, 200));
  rng::FastRng rng(0);
  auto out = corrupt(one, Corruption::MotionBlur, 5, rng);
  ASSERT_TRUE(out.is_ok());
  EXPECT_LE(cv::norm(*out, one, cv::NORM_INF), 1.0);
}

TEST(DegenerateBehaviourTest, FogOnBlackStaysBlack) {
  rng::FastRng rng(0);
  auto out = corrupt(cv::Mat(16, 16, CV_8UC3, cv::Scalar::all(0)), Corruption::Fog, 3, rng);
  EXPECT_EQ(cv::countNonZero(out->reshape(1)), 0);
}

// The blurs and the elastic warp keep a flat frame flat (up to the last-step truncation of float
// noise), in both modes, on every size down to 1 x 1.
TEST(DegenerateBehaviourTest, BlursAndWarpsKeepFlatFramesFlat) {
  for (const Corruption c : {Corruption::DefocusBlur, Corruption::ZoomBlur, Corruption::GlassBlur,
                             Corruption::ElasticTransform}) {
    for (const cv::Size size : {cv::Size(1, 1), cv::Size(2, 2), cv::Size(23, 17)}) {
      for (const cv::Scalar& v :
           {cv::Scalar::all(0), cv::Scalar::all(255), cv::Scalar(80, 120, 160)}) {
        const cv::Mat flat(size, CV_8UC3, v);
        for (int sev = 1; sev <= 5; ++sev) {
          for (const RngMode mode : {RngMode::Numpy, RngMode::Fast}) {
            const cv::Mat out = run(flat, c, sev, mode, 3);
            // Defocus at severity 4 (radius 8 on its 17 x 17 grid): the anti-aliasing blur's
            // reflect-101 border folds the disk's rim back in, the kernel sums to 1.013, and the
            // reference itself brightens flat areas by up to 2 levels.
            const double allowed = c == Corruption::DefocusBlur && sev == 4 ? 2.0 : 1.0;
            EXPECT_LE(cv::norm(out, flat, cv::NORM_INF), allowed)
                << to_string(c) << " sev " << sev << " " << size << " " << to_string(mode);
          }
        }
      }
    }
  }
}

// Spatter's water where the field holds no liquid: the frame comes back unchanged (the reference
// divides 0 by 0 there and returns black).
TEST(DegenerateBehaviourTest, SpatterWithoutLiquidIsTheIdentity) {
  const cv::Mat in = faultline::testing::scene(30, 40);
  const cv::Mat dry = cv::Mat::zeros(in.size(), CV_64F);
  for (int sev = 1; sev <= 3; ++sev)
    EXPECT_EQ(cv::norm(spatter_apply(in, dry, sev, true), in, cv::NORM_INF), 0.0);
}

// Frost on black is the texture alone, b * texture: bright somewhere, never above 255 * b + 1.
TEST(DegenerateBehaviourTest, FrostOnBlackIsTheScaledTexture) {
  const cv::Mat black(40, 60, CV_8UC3, cv::Scalar::all(0));
  for (int sev = 1; sev <= 5; ++sev) {
    rng::NumpyRandomState rng(static_cast<std::uint32_t>(sev));
    const cv::Mat out = *corrupt(black, Corruption::Frost, sev, rng);
    double lo = 0, hi = 0;
    cv::minMaxLoc(out.reshape(1), &lo, &hi);
    EXPECT_GT(hi, 50.0);
    EXPECT_LE(hi, 255.0 * frost_params(sev).texture_weight + 1.0);
  }
}

}  // namespace
}  // namespace faultline::corruption
