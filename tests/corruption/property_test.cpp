// Invariant battery over every corruption x severity 0..5 x mode: shape/type kept, deterministic
// per seed, severity 0 is the identity and draws nothing, bounds per corruption; plus degenerate
// frames.
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
#include "corruption/spatter.hpp"
#include "corruption/test_images.hpp"

namespace faultline::corruption {
namespace {

using Param = std::tuple<Corruption, int, RngMode>;

cv::Mat run(const cv::Mat& in, Corruption c, int sev, RngMode mode, std::uint32_t seed) {
  if (mode == RngMode::Numpy) {
    rng::NumpyRandomState rng(seed);
    auto r = corrupt(in, c, sev, rng);
    EXPECT_TRUE(r.is_ok()) << r.status().to_string();
    return r.is_ok() ? *r : cv::Mat();
  }
  rng::FastRng rng(seed);
  auto r = corrupt(in, c, sev, rng);
  EXPECT_TRUE(r.is_ok()) << r.status().to_string();
  return r.is_ok() ? *r : cv::Mat();
}

double psnr_db(const cv::Mat& a, const cv::Mat& b) {
  const double mse = cv::norm(a, b, cv::NORM_L2SQR) / static_cast<double>(a.total() * a.channels());
  return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

// Sum of absolute differences between horizontal neighbours: blurs and pixelation lower it, noise
// raises it.
double roughness(const cv::Mat& m) {
  cv::Mat a, b;
  cv::absdiff(m(cv::Rect(1, 0, m.cols - 1, m.rows)), m(cv::Rect(0, 0, m.cols - 1, m.rows)), a);
  return cv::sum(a.reshape(1))[0];
}

// Bounds of the imagecorruptions / ISONoise corruptions (docs/faults.md) at severity 1..5.
void ExpectPointwiseBounds(const cv::Mat& in, const cv::Mat& out, Corruption c, int sev) {
  const double mean_in = cv::mean(in.reshape(1))[0], mean_out = cv::mean(out.reshape(1))[0];
  cv::Scalar m_in, sd_in, m_out, sd_out;
  cv::meanStdDev(in.reshape(1), m_in, sd_in);
  cv::meanStdDev(out.reshape(1), m_out, sd_out);
  switch (c) {
    case Corruption::GaussianNoise:
    case Corruption::ShotNoise:
    case Corruption::SpeckleNoise:
    case Corruption::IsoNoise:
      // Zero-mean noise (up to clipping and truncation) that roughens the image.
      EXPECT_NEAR(mean_out, mean_in, 0.25 * mean_in);
      EXPECT_GT(roughness(out), roughness(in));
      break;
    case Corruption::ImpulseNoise: {
      // Each value is kept, or replaced by 0 or 255, in about `amount` of the values.
      cv::Mat changed, extreme, lo, hi;
      cv::compare(out.reshape(1), in.reshape(1), changed, cv::CMP_NE);
      cv::compare(out.reshape(1), 0, lo, cv::CMP_EQ);
      cv::compare(out.reshape(1), 255, hi, cv::CMP_EQ);
      cv::bitwise_and(changed, ~(lo | hi), extreme);
      EXPECT_EQ(cv::countNonZero(extreme), 0);
      const double share = cv::countNonZero(changed) / static_cast<double>(out.total() * 3);
      EXPECT_LT(share, impulse_noise_amount(sev) + 0.03);
      EXPECT_GT(share, 0.3 * impulse_noise_amount(sev));
      break;
    }
    case Corruption::Contrast:
      EXPECT_LT(sd_out[0], 0.45 * sd_in[0]);
      break;
    case Corruption::Saturate: {
      // V (the pixel's max channel) is kept; only saturation moves.
      for (int y = 0; y < in.rows; y += 7) {
        for (int x = 0; x < in.cols; x += 5) {
          const auto p = in.at<cv::Vec3b>(y, x), q = out.at<cv::Vec3b>(y, x);
          EXPECT_NEAR(std::max({q[0], q[1], q[2]}), std::max({p[0], p[1], p[2]}), 1);
        }
      }
      break;
    }
    case Corruption::Pixelate:
    case Corruption::GaussianBlur:
      EXPECT_LT(roughness(out), roughness(in));
      EXPECT_NEAR(mean_out, mean_in, 3.0);
      break;
    case Corruption::JpegCompression:
      EXPECT_GT(psnr_db(out, in), 15.0);
      break;
    // Faultline's stream faults (details in stream_faults_test.cpp): lossy, never a different
    // picture.
    case Corruption::Recompression:
      EXPECT_GT(psnr_db(out, in), 10.0);
      EXPECT_LT(roughness(out), roughness(in));
      break;
    case Corruption::TransportCorruption:
      EXPECT_NEAR(mean_out, mean_in, 0.5 * mean_in);
      break;
    // No yaw rate in this battery: no motion to skew by (its geometry is checked in
    // stream_faults_test.cpp).
    case Corruption::RollingShutter:
      EXPECT_EQ(cv::norm(out, in, cv::NORM_INF), 0.0);
      break;
    default:
      FAIL() << "no bounds for " << to_string(c);
  }
}

// Sum of absolute differences between horizontal and vertical neighbours (all channels).
double total_variation(const cv::Mat& m) {
  cv::Mat f;
  m.convertTo(f, CV_32F);
  const cv::Rect body(0, 0, m.cols - 1, m.rows - 1);
  return cv::norm(f(body), f(body + cv::Point(1, 0)), cv::NORM_L1) +
         cv::norm(f(body), f(body + cv::Point(0, 1)), cv::NORM_L1);
}

// Values of `a` more than `slack` below the same values of `b`.
int count_below(const cv::Mat& a, const cv::Mat& b, int slack) {
  cv::Mat a16, b16, mask;
  a.convertTo(a16, CV_16S);
  b.convertTo(b16, CV_16S, 1.0, -slack);
  cv::compare(a16.reshape(1), b16.reshape(1), mask, cv::CMP_LT);
  return cv::countNonZero(mask);
}

class CorruptionPropertyTest : public ::testing::TestWithParam<Param> {
 protected:
  Corruption type() const { return std::get<0>(GetParam()); }
  int severity() const { return std::get<1>(GetParam()); }
  RngMode mode() const { return std::get<2>(GetParam()); }
};

TEST_P(CorruptionPropertyTest, KeepsShapeAndTypeAndIsDeterministicPerSeed) {
  const cv::Mat in = faultline::testing::scene(64, 96);
  const cv::Mat a = run(in, type(), severity(), mode(), 11);
  const cv::Mat b = run(in, type(), severity(), mode(), 11);
  ASSERT_EQ(a.size(), in.size());
  ASSERT_EQ(a.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
}

TEST_P(CorruptionPropertyTest, SeedMattersOnlyForRandomCorruptions) {
  const cv::Mat in = faultline::testing::scene(64, 96);
  const cv::Mat a = run(in, type(), severity(), mode(), 11);
  const cv::Mat b = run(in, type(), severity(), mode(), 12);
  if (severity() == 0) {
    EXPECT_EQ(cv::norm(a, in, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(b, in, cv::NORM_INF), 0.0);
  } else if (is_random(type())) {
    EXPECT_GT(cv::norm(a, b, cv::NORM_INF), 0.0);
  } else {
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  }
}

TEST_P(CorruptionPropertyTest, SeverityZeroIsIdentityAndDrawsNothing) {
  const cv::Mat in = faultline::testing::scene(33, 17);
  rng::NumpyRandomState rng(5), fresh(5);
  auto out = corrupt(in, type(), 0, rng);
  ASSERT_TRUE(out.is_ok());
  EXPECT_EQ(cv::norm(*out, in, cv::NORM_INF), 0.0);
  EXPECT_EQ(rng.next_u32(), fresh.next_u32());
}

TEST_P(CorruptionPropertyTest, StaysWithinTheCorruptionsBounds) {
  const cv::Mat in = faultline::testing::scene(64, 96);
  const cv::Mat out = run(in, type(), severity(), mode(), 3);
  const double mean_in = cv::mean(in.reshape(1))[0], mean_out = cv::mean(out.reshape(1))[0];
  if (severity() == 0) {
    EXPECT_EQ(cv::norm(out, in, cv::NORM_INF), 0.0);
    return;
  }
  switch (type()) {
    case Corruption::Brightness: {
      cv::Mat lower;
      cv::subtract(in, cv::Scalar::all(1), lower);
      cv::Mat below;
      cv::compare(out.reshape(1), lower.reshape(1), below, cv::CMP_LT);
      EXPECT_EQ(cv::countNonZero(below), 0) << "brightening never darkens";
      EXPECT_GT(mean_out, mean_in);
      break;
    }
    case Corruption::ColorQuant: {
      cv::Mat expected;
      cv::bitwise_and(in, cv::Scalar::all(color_quant_mask(severity())), expected);
      EXPECT_EQ(cv::norm(out, expected, cv::NORM_INF), 0.0);
      break;
    }
    case Corruption::Dark:
      EXPECT_LT(mean_out, 0.75 * mean_in);
      break;
    case Corruption::Snow:
      EXPECT_GT(mean_out, mean_in);
      break;
    case Corruption::Fog:
    case Corruption::MotionBlur:
      EXPECT_NEAR(mean_out, mean_in, 0.5 * mean_in);
      break;
    case Corruption::DefocusBlur:
    case Corruption::ZoomBlur:
    case Corruption::GlassBlur:
      // Blurs keep the mean (less the truncation) and smooth: less total variation than the input.
      EXPECT_NEAR(mean_out, mean_in, 0.05 * mean_in);
      EXPECT_LT(total_variation(out), total_variation(in));
      break;
    case Corruption::ElasticTransform:
      EXPECT_NEAR(mean_out, mean_in, 0.05 * mean_in);
      break;
    case Corruption::Frost: {
      // a * image + b * texture with b * texture >= 0: never below trunc(a * image).
      cv::Mat floor_in;
      in.convertTo(floor_in, CV_8UC3, frost_params(severity()).image_weight, -0.5);
      EXPECT_EQ(count_below(out, floor_in, 1), 0);
      break;
    }
    case Corruption::Spatter:
      if (!spatter_params(severity()).mud) {
        EXPECT_EQ(count_below(out, in, 1), 0) << "water only adds";
      } else {
        // Mud blends each value towards the mud colour (63, 42, 20 in stored order): between the
        // two.
        const cv::Mat mud(in.size(), CV_8UC3, cv::Scalar(63, 42, 20));
        cv::Mat lo, hi;
        cv::min(in, mud, lo);
        cv::max(in, mud, hi);
        EXPECT_EQ(count_below(out, lo, 1), 0);
        EXPECT_EQ(count_below(hi, out, 1), 0);
      }
      break;
    // Faultline's own sensor faults: their bounds and behaviour are in sensor_fault_test.cpp.
    case Corruption::Soiling:
    case Corruption::WaterDrops:
    case Corruption::Glare:
    case Corruption::ExposureFlicker:
      break;
    default:
      ExpectPointwiseBounds(in, out, type(), severity());
      break;
  }
}

INSTANTIATE_TEST_SUITE_P(
    AllTypes, CorruptionPropertyTest,
    ::testing::Combine(::testing::ValuesIn(kAllCorruptions), ::testing::Range(0, 6),
                       ::testing::Values(RngMode::Numpy, RngMode::Fast)),
    [](const ::testing::TestParamInfo<Param>& p) {
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
      return name + "Sev" + std::to_string(std::get<1>(p.param)) +
             (std::get<2>(p.param) == RngMode::Numpy ? "Numpy" : "Fast");
    });

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

TEST(BrightnessPathsTest, TablePathEqualsHsvMirrorOnEveryColourClass) {
  // Random colours plus every tie pattern (ch0 == ch1, ch0 == ch2, ch1 == ch2, all three), at every
  // severity: the fast path reads tied channels from the max/min roles, so each pattern must match
  // the HSV mirror.
  cv::Mat img(128, 128, CV_8UC3);
  std::uint32_t s = 99;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      s = s * 1664525u + 1013904223u;
      const auto a = static_cast<uchar>(s >> 24), b = static_cast<uchar>(s >> 16),
                 c = static_cast<uchar>(s >> 8);
      switch (x % 5) {
        case 0:
          img.at<cv::Vec3b>(y, x) = cv::Vec3b(a, b, c);
          break;
        case 1:
          img.at<cv::Vec3b>(y, x) = cv::Vec3b(a, a, c);
          break;
        case 2:
          img.at<cv::Vec3b>(y, x) = cv::Vec3b(b, c, b);
          break;
        case 3:
          img.at<cv::Vec3b>(y, x) = cv::Vec3b(c, b, b);
          break;
        default:
          img.at<cv::Vec3b>(y, x) = cv::Vec3b(a, a, a);
          break;
      }
    }
  }
  for (int sev = 1; sev <= 5; ++sev) {
    EXPECT_EQ(cv::norm(brightness_fast(img, sev), brightness_exact(img, sev), cv::NORM_INF), 0.0)
        << sev;
  }
}

TEST(BrightnessPathsTest, TablePathEqualsHsvMirrorOnEveryColour) {
  // All 2^24 colours once (4096 x 4096, also exercising the 8-pixel vector path and its scalar tail
  // on a width that is a multiple of 8 and on an odd crop), at every severity.
  cv::Mat all(4096, 4096, CV_8UC3);
  for (int i = 0; i < (1 << 24); ++i) {
    all.data[3 * i] = static_cast<uchar>(i);
    all.data[3 * i + 1] = static_cast<uchar>(i >> 8);
    all.data[3 * i + 2] = static_cast<uchar>(i >> 16);
  }
  const cv::Mat odd = all(cv::Rect(3, 5, 333, 197));
  for (int sev = 1; sev <= 5; ++sev) {
    EXPECT_EQ(cv::norm(brightness_fast(all, sev), brightness_exact(all, sev), cv::NORM_INF), 0.0)
        << sev;
    EXPECT_EQ(cv::norm(brightness_fast(odd, sev), brightness_exact(odd, sev), cv::NORM_INF), 0.0)
        << sev;
  }
}

TEST(ColorQuantTest, MatchesABitwiseAndOnCropsAndDeeperImages) {
  // A crop of a wider frame (rows not contiguous: the per-row path) and 16-bit data (OpenCV's AND)
  // at every severity.
  const cv::Mat wide = faultline::testing::scene(97, 211);
  const cv::Mat crop = wide(cv::Rect(5, 3, 131, 77));
  ASSERT_FALSE(crop.isContinuous());
  cv::Mat deep;
  wide.convertTo(deep, CV_16UC3, 257.0);
  for (int sev = 1; sev <= 5; ++sev) {
    const int m = color_quant_mask(sev);
    for (const cv::Mat& in : {wide, crop, deep}) {
      cv::Mat expected;
      cv::bitwise_and(in, cv::Scalar::all(m), expected);
      const cv::Mat out = color_quant(in, sev);
      ASSERT_EQ(out.type(), in.type());
      EXPECT_EQ(cv::norm(out, expected, cv::NORM_INF), 0.0)
          << sev << " " << in.cols << "x" << in.rows;
    }
  }
}

// Max abs difference between the fast and the exact brightness path at one severity.
double BrightnessFastVsExact(const cv::Mat& img, int severity) {
  return cv::norm(brightness_fast(img, severity), brightness_exact(img, severity), cv::NORM_INF);
}

TEST(BrightnessPathsTest, TiedPixelsMatchHsvMirrorForEveryValuePair) {
  // Every pixel with two equal channels: 3 tie patterns x tied value x other value, which covers
  // ties at the max, ties at the min (also where p lies on a truncation boundary) and greys; the
  // fast path gives them the max and min roles without a table of their own. One row per (pattern,
  // tied value), so each 8-pixel step mixes several other values and grey runs start mid-row.
  cv::Mat img(3 * 256, 256, CV_8UC3);
  for (int pattern = 0; pattern < 3; ++pattern) {
    for (int tied = 0; tied < 256; ++tied) {
      auto* row = img.ptr<cv::Vec3b>(pattern * 256 + tied);
      for (int other = 0; other < 256; ++other) {
        const auto a = static_cast<uchar>(tied), b = static_cast<uchar>(other);
        row[other] = pattern == 0 ? cv::Vec3b(a, a, b)
                                  : (pattern == 1 ? cv::Vec3b(b, a, a) : cv::Vec3b(a, b, a));
      }
    }
  }
  // The transposed image puts the same pixels in steps where the tied value varies instead.
  const cv::Mat across = img.t();
  for (int sev = 1; sev <= 5; ++sev) {
    EXPECT_EQ(BrightnessFastVsExact(img, sev), 0.0) << "severity " << sev;
    EXPECT_EQ(BrightnessFastVsExact(across, sev), 0.0) << "severity " << sev;
  }
}

TEST(BrightnessPathsTest, MiddleChannelsOnATruncationBoundaryMatchHsvMirror) {
  // Distinct channels whose middle value m has an integer closed form m * V2 / V * 255 (float noise
  // then decides the truncation, and the fast path reads the HSV path's result from its ambiguity
  // table): every such (v, m) at each severity, with min values 0, m / 2 and m - 1, in all six
  // channel orders.
  const int orders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int sev = 1; sev <= 5; ++sev) {
    const int k = 51 * sev;  // 510 * c: V2 * 255 = v + k / 2, saturating at 255
    std::vector<cv::Vec3b> pixels;
    for (int v = 2; v < 256; ++v) {
      for (int m = 1; m < v; ++m) {
        const int num = m * std::min(2 * v + k, 510), den = 2 * v;
        if (num % den != 0) continue;
        for (const int mn : {0, m / 2, m - 1}) {
          for (const auto& order : orders) {
            cv::Vec3b px;
            px[order[0]] = static_cast<uchar>(v);
            px[order[1]] = static_cast<uchar>(m);
            px[order[2]] = static_cast<uchar>(mn);
            pixels.push_back(px);
          }
        }
      }
    }
    ASSERT_GT(pixels.size(), 1000u) << "severity " << sev;
    const cv::Mat img(1, static_cast<int>(pixels.size()), CV_8UC3, pixels.data());
    EXPECT_EQ(BrightnessFastVsExact(img, sev), 0.0) << "severity " << sev;
  }
}

TEST(BrightnessPathsTest, FlatRegionsOfRenderedFramesMatchHsvMirror) {
  // A rendered-looking frame: flat rectangles whose edges fall anywhere within the 8-pixel steps
  // (the fast path reuses a step's output when the next step repeats its input), in colours that
  // hit every table entry kind: the middle channel exactly on a truncation boundary in all six
  // channel orders ((1, 48, 102): 48 * 153 / 102 = 72 at severity 2, as in flat regions of our
  // synthetic nuScenes frames), ties at the max and at the min, greys, black (the repeat check's
  // initial state) and white; plus a noisy band and a stripe pattern repeating every 8 pixels.
  const std::vector<cv::Vec3b> colours = {
      {1, 48, 102},    {1, 102, 48}, {48, 1, 102}, {48, 102, 1},   {102, 1, 48},   {102, 48, 1},
      {234, 215, 194}, {70, 70, 70}, {12, 12, 88}, {102, 102, 48}, {48, 102, 102}, {0, 0, 0},
      {255, 255, 255}, {24, 72, 0},  {0, 79, 166}, {39, 119, 0},   {255, 0, 255},  {40, 200, 240}};
  cv::Mat img(181, 997, CV_8UC3, cv::Scalar::all(0));
  std::uint32_t s = 7;
  auto next = [&s] { return s = s * 1664525u + 1013904223u; };
  for (int k = 0; k < 60; ++k) {
    const int x = static_cast<int>(next() % 900), y = static_cast<int>(next() % 160);
    const int w = 1 + static_cast<int>(next() % 300), h = 1 + static_cast<int>(next() % 90);
    const cv::Vec3b c = colours[next() % colours.size()];
    img(cv::Rect(x, y, std::min(w, img.cols - x), std::min(h, img.rows - y)))
        .setTo(cv::Scalar(c[0], c[1], c[2]));
  }
  for (int y = 150; y < 160; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const std::uint32_t r = next();
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(r >> 8), static_cast<uchar>(r >> 16),
                                          static_cast<uchar>(r >> 24));
    }
  }
  for (int y = 165; y < 181; ++y) {
    for (int x = 0; x < img.cols; ++x)
      img.at<cv::Vec3b>(y, x) = colours[static_cast<std::size_t>(x % 8)];
  }
  const cv::Mat black(40, 64, CV_8UC3, cv::Scalar::all(0));
  for (int sev = 1; sev <= 5; ++sev) {
    EXPECT_EQ(BrightnessFastVsExact(img, sev), 0.0) << "severity " << sev;
    EXPECT_EQ(BrightnessFastVsExact(img(cv::Rect(5, 3, 611, 170)), sev), 0.0) << "severity " << sev;
    EXPECT_EQ(BrightnessFastVsExact(black, sev), 0.0) << "severity " << sev;
  }
}

TEST(DarkFastTablesTest, EachFrameUsesTheTablesOfItsOwnRange) {
  // The sampling tables are cached per (severity, image min, image max): a frame with another range
  // right after a full-range frame must follow its own stretch. Severity 2 (c = 0.4): the image
  // maximum maps to a mean of about 255 * 0.4 - 0.5 and the image minimum to pure read noise, mean
  // about 1.6 (spec section 3).
  rng::FastRng rng(5);
  cv::Mat full(64, 64, CV_8UC3);
  cv::randu(full, 0, 256);
  full.at<cv::Vec3b>(0, 0) = cv::Vec3b(0, 255, 0);
  (void)dark_fast(full, 2, rng);
  cv::Mat narrow(100, 100, CV_8UC3, cv::Scalar::all(50));
  narrow(cv::Rect(0, 0, 100, 50)).setTo(cv::Scalar::all(100));
  const cv::Mat out = dark_fast(narrow, 2, rng);
  const double at_hi = cv::mean(out(cv::Rect(0, 0, 100, 50)))[0];
  const double at_lo = cv::mean(out(cv::Rect(0, 50, 100, 50)))[0];
  EXPECT_NEAR(at_hi, 255 * 0.4 - 0.5, 1.0);
  EXPECT_NEAR(at_lo, 1.6, 0.6);
}

TEST(FogFractalTest, CropEqualsFullMapCropAndConsumesTheSameDraws) {
  for (int n : {4, 64, 256}) {
    rng::NumpyRandomState a(8), b(8);
    const cv::Mat full = plasma_fractal(n, 1.7, a);
    const cv::Mat crop = plasma_fractal_crop(n, 1.7, b, n / 2 + 1, n - 1);
    EXPECT_EQ(cv::norm(full(cv::Rect(0, 0, n - 1, n / 2 + 1)), crop, cv::NORM_INF), 0.0) << n;
    EXPECT_EQ(a.random_sample(), b.random_sample());
    double lo = 0, hi = 0;
    cv::minMaxLoc(full, &lo, &hi);
    EXPECT_EQ(lo, 0.0);
    EXPECT_EQ(hi, 1.0);
  }
}

TEST(InputValidationTest, RejectsEmptyWrongTypeAndBadSeverity) {
  rng::FastRng rng(0);
  EXPECT_EQ(corrupt(cv::Mat(), Corruption::Fog, 1, rng).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(corrupt(cv::Mat(4, 4, CV_8UC1), Corruption::Fog, 1, rng).status().code(),
            StatusCode::kUnsupported);
  EXPECT_EQ(corrupt(cv::Mat(4, 4, CV_8UC3), Corruption::Fog, 6, rng).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(corrupt(cv::Mat(4, 4, CV_8UC3), Corruption::Fog, -1, rng).status().code(),
            StatusCode::kInvalidArgument);
}

TEST(NamesTest, RoundTripAndLevelMapping) {
  for (Corruption c : kAllCorruptions) EXPECT_EQ(corruption_from_string(to_string(c)), c);
  EXPECT_FALSE(corruption_from_string("rain").has_value());
  EXPECT_EQ(corruption_from_string("low_light"), Corruption::Dark);
  EXPECT_EQ(severity_for(Corruption::Brightness, Level::Easy), 2);
  EXPECT_EQ(severity_for(Corruption::Fog, Level::Mid), 4);
  EXPECT_EQ(severity_for(Corruption::MotionBlur, Level::Hard), 5);
  EXPECT_EQ(severity_for(Corruption::ColorQuant, Level::Hard), 3);
  EXPECT_EQ(severity_for(Corruption::Snow, Level::Easy), 1);
  EXPECT_EQ(severity_for(Corruption::Dark, Level::Easy), 2);
  EXPECT_EQ(severity_for(Corruption::Dark, Level::Hard), 4);
  EXPECT_EQ(corruption_from_string("elastic_transform"), Corruption::ElasticTransform);
  EXPECT_EQ(severity_for(Corruption::Frost, Level::Mid), 4);
  EXPECT_FALSE(is_random(Corruption::DefocusBlur));
  EXPECT_FALSE(is_random(Corruption::ZoomBlur));
  EXPECT_TRUE(is_random(Corruption::GlassBlur));
}

}  // namespace
}  // namespace faultline::corruption
