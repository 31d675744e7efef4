// The exact and fast paths agree (brightness table vs HSV mirror, colour quantisation, dark's
// per-range tables, fog crops), input validation, and the corruption names and level mapping
// (split from property_test.cpp).
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
