// Invariant battery over every corruption x severity 0..5 x mode: shape/type kept, deterministic
// per seed, severity 0 is the identity and draws nothing, bounds per corruption. Degenerate frames
// are in degenerate_test.cpp, the exact-vs-fast paths in paths_test.cpp.
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

using Param = std::tuple<Corruption, int, RngMode>;

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

}  // namespace
}  // namespace faultline::corruption
