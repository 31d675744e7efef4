// Motion blur with the manifest's exact angle injected: exact in numpy mode, float32 within the
// spec's bound.
#include "corruption/motion_blur.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "corruption/corrupt.hpp"
#include "corruption/golden_cases.hpp"
#include "corruption/motion_kernel.hpp"
#include "corruption/simd_kernels.hpp"
#include "rng/golden_json.hpp"

namespace faultline::testing {
namespace {

// Fast mode's allowance (spec §11): at most 1 off, on at most 0.2 % of the values.
void ExpectWithinFastTolerance(const cv::Mat& fast, const cv::Mat& exact, const std::string& what) {
  EXPECT_LE(max_abs_diff(fast, exact), 1.0) << what;
  EXPECT_LE(fraction_different(fast, exact), 0.002) << what;
}

std::vector<GoldenCase> motion_cases() {
  std::vector<GoldenCase> out;
  for (const auto& c : load_golden_cases()) {
    if (c.type == corruption::Corruption::MotionBlur) out.push_back(c);
  }
  return out;
}

TEST(MotionBlurAngleTest, InjectedAngleIsExactAndDrawsNothing) {
  const auto cases = motion_cases();
  ASSERT_EQ(cases.size(), 15u);
  for (const auto& c : cases) {
    const cv::Mat in = read_golden_png(c.input_file);
    rng::NumpyRandomState rng(c.seed.value_or(0));
    corruption::CorruptOptions opt;
    opt.angle_deg = c.angle_deg;
    auto out = corruption::corrupt(in, c.type, c.severity, rng, opt);
    ASSERT_TRUE(out.is_ok());
    EXPECT_EQ(compare_with_reference(*out, c), "");
    rng::NumpyRandomState fresh(c.seed.value_or(0));
    EXPECT_EQ(rng.random_sample(), fresh.random_sample()) << "an injected angle must not draw";
  }
}

TEST(MotionBlurAngleTest, FastModeWithInjectedAngleIsWithinFloat32Bound) {
  for (const auto& c : motion_cases()) {
    const cv::Mat in = read_golden_png(c.input_file);
    const cv::Mat ref = reference_output(c);
    rng::FastRng rng(1);
    corruption::CorruptOptions opt;
    opt.angle_deg = c.angle_deg;
    auto out = corruption::corrupt(in, c.type, c.severity, rng, opt);
    ASSERT_TRUE(out.is_ok());
    EXPECT_LE(max_abs_diff(*out, ref), 1.0) << c.name;
    EXPECT_LE(fraction_different(*out, ref), 0.002) << c.name;
  }
}

TEST(MotionBlurPathsTest, NumpyEqualsFloat64AndFastIsWithinToleranceOnNoiseFlatAndGradientContent) {
  // Noise (sums far from integers), flat bands (sums on an integer, decided by the kernel's last
  // ulps) and a smooth gradient, with a width that is not a multiple of the 64-value block, at
  // every severity and many angles.
  cv::Mat img(96, 203, CV_8UC3);
  std::uint32_t s = 7;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      s = s * 1664525u + 1013904223u;
      cv::Vec3b px(static_cast<uchar>(s >> 24), static_cast<uchar>(s >> 16),
                   static_cast<uchar>(s >> 8));
      if (y < 32) px = cv::Vec3b(static_cast<uchar>(y < 16 ? 255 : 37), 0, 128);
      if (y >= 64)
        px = cv::Vec3b(static_cast<uchar>(x), static_cast<uchar>(y * 2), static_cast<uchar>(x + y));
      img.at<cv::Vec3b>(y, x) = px;
    }
  }
  for (int sev = 1; sev <= 5; ++sev) {
    for (double angle : {-45.0, -33.3, -10.0, 0.0, 0.7, 22.5, 44.99}) {
      const cv::Mat fast = corruption::motion_blur_fast(img, sev, angle);
      const cv::Mat numpy = corruption::motion_blur_numpy(img, sev, angle);
      const cv::Mat exact = corruption::motion_blur_exact(img, sev, angle);
      ExpectWithinFastTolerance(
          fast, exact, "severity " + std::to_string(sev) + " angle " + std::to_string(angle));
      EXPECT_EQ(max_abs_diff(numpy, exact), 0.0) << "severity " << sev << " angle " << angle;
    }
  }
}

TEST(MotionBlurPathsTest, NumpyEqualsFloat64AndFastIsWithinToleranceOnNearFlatContent) {
  // Flat regions with sparse speckles of +-1..3 (JPEG-like residue on synthetic or overexposed
  // frames): most sums sit on an integer, many with every tap equal (resolved from the flat table)
  // and many with one tap different where the half-Gaussian weight is ~1e-8 (resolved with the
  // vector float64 sum). Plain float32 sums get several % of these wrong; numpy mode must equal the
  // float64 path, fast mode stay within its tolerance.
  cv::Mat img(120, 333, CV_8UC3);
  std::uint32_t s = 11;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const int base = x < 111 ? 0 : (x < 222 ? 128 : 255);
      cv::Vec3b px(static_cast<uchar>(base), static_cast<uchar>(y < 60 ? 37 : 200),
                   static_cast<uchar>(base / 2));
      s = s * 1664525u + 1013904223u;
      if ((s >> 24) < 3) {  // ~1 % of pixels
        const int d = static_cast<int>((s >> 8) % 7) - 3;
        for (int c = 0; c < 3; ++c) px[c] = static_cast<uchar>(std::clamp(px[c] + d, 0, 255));
      }
      img.at<cv::Vec3b>(y, x) = px;
    }
  }
  for (int sev = 1; sev <= 5; ++sev) {
    for (double angle : {-45.0, -12.5, 0.0, 30.0}) {
      const cv::Mat exact = corruption::motion_blur_exact(img, sev, angle);
      ExpectWithinFastTolerance(
          corruption::motion_blur_fast(img, sev, angle), exact,
          "severity " + std::to_string(sev) + " angle " + std::to_string(angle));
      EXPECT_EQ(max_abs_diff(corruption::motion_blur_numpy(img, sev, angle), exact), 0.0)
          << "severity " << sev << " angle " << angle;
    }
  }
}

TEST(MotionBlurPathsTest, FlatStretchesEqualFloat64InNumpyModeAndWithinToleranceInFastMode) {
  // Rows are cut into stretches where every tap reads one colour (filled from the flat table
  // without sums) and the rest. Colours that differ in one channel by 1, horizontal bands that
  // change every few rows (flat along a row, not along the streak), 1-pixel stripes, saturated
  // regions and edge columns that differ from their neighbours, at widths that are not a multiple
  // of the block, a narrow image and one channel.
  auto scene = [](int rows, int cols, int channels) {
    cv::Mat img(rows, cols, CV_8UC(channels));
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < cols; ++x) {
        int v[3] = {10, 20, 30};
        if (x >= cols / 3) v[2] = 31;  // one channel one step apart
        if (y >= rows / 4 && y < rows / 2) v[0] = (y / 3) % 2 ? 200 : 199;  // bands along the rows
        if (y >= rows / 2 && x < cols / 2) v[1] = 255, v[0] = 0;            // saturated block
        if (y >= rows / 2 && x >= cols / 2 && x < cols / 2 + 24)
          v[2] = x % 2 ? 90 : 91;                      // 1-pixel stripes
        if (x == 0 || x == cols - 1) v[0] = 77;        // edge columns
        if (y == rows - 1 && x % 50 < 25) v[1] = 254;  // bottom edge row
        for (int c = 0; c < channels; ++c)
          img.ptr<uchar>(y)[x * channels + c] = static_cast<uchar>(v[c]);
      }
    }
    return img;
  };
  for (const cv::Mat& img : {scene(150, 517, 3), scene(64, 45, 3), scene(97, 301, 1)}) {
    for (int sev = 1; sev <= 5; ++sev) {
      for (double angle : {-45.0, -30.0, -3.0, 0.0, 10.0, 44.99}) {
        const cv::Mat exact = corruption::motion_blur_exact(img, sev, angle);
        EXPECT_EQ(max_abs_diff(corruption::motion_blur_numpy(img, sev, angle), exact), 0.0)
            << img.cols << "x" << img.rows << "x" << img.channels() << " severity " << sev
            << " angle " << angle;
        ExpectWithinFastTolerance(corruption::motion_blur_fast(img, sev, angle), exact,
                                  std::to_string(img.cols) + "x" + std::to_string(img.rows) + "x" +
                                      std::to_string(img.channels()) + " severity " +
                                      std::to_string(sev) + " angle " + std::to_string(angle));
      }
    }
  }
}

TEST(MotionBlurAngleTest, OffsetsMatchManifest) {
  const auto doc = load_golden_json("manifest.json");
  int checked = 0;
  for (const auto& o : doc["outputs"].GetArray()) {
    if (std::string(o["corruption"].GetString()) != "motion_blur") continue;
    const double angle = exact_double(o["rng_derived"]["angle_deg"]["hex"]);
    const int width = o["constants"]["kernel_width"].GetInt();
    const auto offsets = corruption::motion_offsets(angle, width);
    const auto& expected = o["rng_derived"]["offsets_dy_dx"];
    ASSERT_EQ(offsets.size(), expected.Size());
    for (rapidjson::SizeType i = 0; i < expected.Size(); ++i) {
      EXPECT_EQ(offsets[i].dy, expected[i][0].GetInt());
      EXPECT_EQ(offsets[i].dx, expected[i][1].GetInt());
    }
    ++checked;
  }
  EXPECT_EQ(checked, 15);
}

TEST(MotionBlurAngleTest, NonFiniteInjectedAngleIsInvalidInBothModes) {
  const cv::Mat in(8, 8, CV_8UC3, cv::Scalar(10, 20, 30));
  for (const double angle : {std::nan(""), HUGE_VAL, -HUGE_VAL}) {
    corruption::CorruptOptions opt;
    opt.angle_deg = angle;
    rng::NumpyRandomState numpy(1);
    rng::FastRng fast(1);
    const auto a = corruption::corrupt(in, corruption::Corruption::MotionBlur, 3, numpy, opt);
    const auto b = corruption::corrupt(in, corruption::Corruption::MotionBlur, 3, fast, opt);
    ASSERT_FALSE(a.is_ok());
    ASSERT_FALSE(b.is_ok());
    EXPECT_EQ(a.status().code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(b.status().code(), StatusCode::kInvalidArgument);
  }
}

TEST(MotionBlurKernelTest, TablesExistForEveryUsedPairAndSumToOne) {
  const int pairs[][2] = {{10, 3}, {15, 5}, {15, 8}, {15, 12}, {20, 15},
                          {10, 4}, {12, 4}, {12, 8}, {12, 12}};
  for (const auto& p : pairs) {
    const auto* k = corruption::find_tabulated_kernel(p[0], p[1]);
    ASSERT_NE(k, nullptr);
    EXPECT_EQ(k->width, 2 * p[0] + 1);
    double sum = 0;
    for (int i = 0; i < k->width; ++i) sum += k->weights[i];
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
  EXPECT_EQ(corruption::find_tabulated_kernel(3, 3), nullptr);
}

// The compiled tables are the reference's kernels bit for bit (kernels.json holds them as hex
// doubles).
TEST(MotionBlurKernelTest, TablesEqualTheReferenceKernelsExactly) {
  const auto doc = load_golden_json("kernels.json");
  int tables = 0;
  for (const auto& entry : doc["kernels"].GetObject()) {
    const auto& k = entry.value;
    const auto* table =
        corruption::find_tabulated_kernel(k["radius"].GetInt(), k["sigma"].GetInt());
    ASSERT_NE(table, nullptr) << entry.name.GetString();
    const auto& weights = k["k_hex"];
    ASSERT_EQ(static_cast<rapidjson::SizeType>(table->width), weights.Size())
        << entry.name.GetString();
    for (rapidjson::SizeType i = 0; i < weights.Size(); ++i) {
      EXPECT_EQ(table->weights[i], exact_double(weights[i]))
          << entry.name.GetString() << " k_" << i;
    }
    ++tables;
  }
  EXPECT_EQ(tables, 9);
}

TEST(FastBlurKernelTest, TruncatesFloat64SumsAndTakesFlatLanesFromTheTable) {
  // Rows of random bytes with some lanes flat across all taps, a float32 tail of 3 left-out taps,
  // 211 values (vector blocks of 96/64/32 plus a scalar tail). The flat table here deliberately
  // differs from the sums (v -> v / 2): flat lanes whose sum lies on an integer must come from it,
  // every other value must be floor of the float64 sum over all taps (random sums are far from
  // integers), clamped to 0..255.
  constexpr int kTaps = 9, kTaps32 = 6;
  constexpr std::size_t kN = 211;
  const double w64[kTaps] = {0.31, 0.22, 0.16, 0.11, 0.08, 0.06, 1e-7, 5e-8, 2e-8};
  std::vector<std::vector<float>> rows(kTaps, std::vector<float>(kN));
  std::uint32_t s = 3;
  for (std::size_t j = 0; j < kN; ++j) {
    const bool flat_lane = j % 17 == 5;
    for (int i = 0; i < kTaps; ++i) {
      s = s * 1664525u + 1013904223u;
      rows[static_cast<std::size_t>(i)][j] =
          flat_lane ? static_cast<float>(j % 256) : static_cast<float>(s >> 24);
    }
  }
  std::int32_t flat[256];
  for (int v = 0; v < 256; ++v) flat[v] = v / 2;
  std::vector<const float*> ptrs;
  for (const auto& r : rows) ptrs.push_back(r.data());
  double used = 0;
  for (const double w : w64) used += w;
  for (double scale : {1.0, 1.0 / used}) {  // sums below 255, and sums that reach 255 (clamped)
    double ws64[kTaps];
    float ws32[kTaps];
    for (int i = 0; i < kTaps; ++i) ws64[i] = w64[i] * scale, ws32[i] = static_cast<float>(ws64[i]);
    // The band covers the float32 error of 6 taps and the left-out tail (<= 255 * 1.7e-7).
    const float band = static_cast<float>(14 * 256 * 0x1p-24 + 255 * 1.7e-7 * scale);
    std::vector<std::uint8_t> dst(kN);
    corruption::simd::weighted_rows_truncate_fast(ptrs.data(), ws32, kTaps32, ws64, kTaps, band,
                                                  flat, dst.data(), kN);
    for (std::size_t j = 0; j < kN; ++j) {
      double sum = 0;
      for (int i = 0; i < kTaps; ++i) sum += ws64[i] * rows[static_cast<std::size_t>(i)][j];
      // Flat lanes consult the table where their sum lands on an integer (scaled weights summing to
      // 1).
      const bool from_table = j % 17 == 5 && scale != 1.0;
      const int expected = from_table ? flat[j % 256] : static_cast<int>(std::min(sum, 255.0));
      EXPECT_EQ(dst[j], expected) << "value " << j << " scale " << scale;
    }
  }
}

TEST(HalfRowsTest, BytesRoundTripThroughBinary16Exactly) {
  // The motion-blur ring stores bytes as binary16; both conversions must be exact for every byte.
  EXPECT_EQ(corruption::simd::half_of_byte(1), 0x3C00);    // 1.0
  EXPECT_EQ(corruption::simd::half_of_byte(255), 0x5BF8);  // 255.0
  std::uint8_t bytes[256 + 13];
  std::uint16_t halves[256 + 13];
  for (int v = 0; v < 256 + 13; ++v) bytes[v] = static_cast<std::uint8_t>(v * 37);
  corruption::simd::u8_to_half(bytes, halves, 256 + 13);  // vector body + scalar tail
  for (int v = 0; v < 256 + 13; ++v) {
    EXPECT_EQ(halves[v], corruption::simd::half_of_byte(bytes[v])) << v;
    EXPECT_EQ(corruption::simd::byte_of_half(halves[v]), static_cast<float>(bytes[v])) << v;
  }
}

}  // namespace
}  // namespace faultline::testing
