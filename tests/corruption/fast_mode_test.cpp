// fast mode against the goldens (the reference's arrays, see reference_output): exact where there
// is no randomness or the random field is injected, and within the seed-to-seed ranges of
// seed_to_seed_stats.json (golden README margins) where it is not.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "corruption/corrupt.hpp"
#include "corruption/fog.hpp"
#include "corruption/golden_cases.hpp"
#include "rng/golden_json.hpp"

namespace faultline::testing {
namespace {

using corruption::Corruption;

double psnr(const cv::Mat& a, const cv::Mat& b) {
  const double mse = cv::norm(a, b, cv::NORM_L2SQR) / static_cast<double>(a.total() * a.channels());
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

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
    for (int v = 0; v < 256; ++v)
      total += std::fabs(ha[static_cast<std::size_t>(v)] - hb[static_cast<std::size_t>(v)]);
  }
  return total / 3.0 / static_cast<double>(a.total());
}

class FastGoldenTest : public ::testing::TestWithParam<GoldenCase> {
 protected:
  static void SetUpTestSuite() {
    stats_ = new rapidjson::Document(load_golden_json("seed_to_seed_stats.json"));
  }
  static void TearDownTestSuite() {
    delete stats_;
    stats_ = nullptr;
  }
  static rapidjson::Document* stats_;
};
rapidjson::Document* FastGoldenTest::stats_ = nullptr;

TEST_P(FastGoldenTest, MatchesGoldenExactlyOrWithinSeedToSeedRange) {
  const GoldenCase c = load_golden_case(GetParam());
  const cv::Mat in = read_golden_png(c.input_file);
  const cv::Mat ref = reference_output(c);
  rng::FastRng rng(1000 + c.seed.value_or(0));
  auto out = corruption::corrupt(in, c.type, c.severity, rng);
  ASSERT_TRUE(out.is_ok());
  switch (c.type) {
    case Corruption::Brightness:
    case Corruption::ColorQuant:
      EXPECT_EQ(max_abs_diff(*out, ref), 0.0);
      return;
    case Corruption::MotionBlur: {
      // Angle injected: within fast mode's allowance (at most 1 off on at most 0.2 % of the
      // values).
      rng::FastRng r2(1);
      corruption::CorruptOptions opt;
      opt.angle_deg = c.angle_deg;
      const cv::Mat blurred = *corruption::corrupt(in, c.type, c.severity, r2, opt);
      EXPECT_LE(max_abs_diff(blurred, ref), 1.0);
      EXPECT_LE(fraction_different(blurred, ref), 0.002);
      return;
    }
    case Corruption::Fog: {
      // Exact blend stage: numpy's fractal injected into the fast blend (float32: at most 1 level
      // off, rarely).
      rng::NumpyRandomState np(*c.seed);
      const auto p = corruption::fog_params(c.severity);
      const cv::Mat fractal =
          corruption::plasma_fractal(corruption::fog_map_size(in.rows, in.cols), p.decay, np);
      cv::Mat field;
      fractal(cv::Rect(0, 0, in.cols, in.rows)).convertTo(field, CV_32F);
      const cv::Mat blended = corruption::fog_blend_fast(in, field, p.strength);
      EXPECT_LE(max_abs_diff(blended, ref), 1.0);
      EXPECT_LT(fraction_different(blended, ref), 0.01);
      return;
    }
    case Corruption::Dark:
    case Corruption::Snow: {
      const std::string key = std::string(corruption::to_string(c.type)) + "/" + c.input + "/sev" +
                              std::to_string(c.severity);
      const auto& s = (*stats_)["stats"][key.c_str()];
      const double psnr_margin = c.type == Corruption::Dark ? 0.3 : 0.5;
      // Averaged over four fast seeds: the golden ranges come from only five reference seeds.
      const int seeds = 4;
      double p = 0, h = 0, mean = 0, sd = 0;
      for (int k = 0; k < seeds; ++k) {
        rng::FastRng r(static_cast<std::uint64_t>(7000 + 31 * k) + c.seed.value_or(0));
        const cv::Mat o = *corruption::corrupt(in, c.type, c.severity, r);
        cv::Scalar m, d;
        cv::meanStdDev(o.reshape(1), m, d);
        p += psnr(o, ref) / seeds;
        h += hist_l1(o, ref) / seeds;
        mean += m[0] / seeds;
        sd += d[0] / seeds;
      }
      EXPECT_GE(p, s["psnr_db_between_seeds"][0].GetDouble() - psnr_margin) << key;
      EXPECT_LE(p, s["psnr_db_between_seeds"][1].GetDouble() + psnr_margin) << key;
      EXPECT_LE(h, 1.5 * s["hist_l1_between_seeds"][1].GetDouble()) << key;
      const double mean_margin = c.type == Corruption::Dark ? 0.3 : 1.0;
      EXPECT_GE(mean, s["mean"][0].GetDouble() - mean_margin) << key;
      EXPECT_LE(mean, s["mean"][1].GetDouble() + mean_margin) << key;
      if (c.type == Corruption::Dark) {
        EXPECT_GE(sd, s["std"][0].GetDouble() - 0.3) << key;
        EXPECT_LE(sd, s["std"][1].GetDouble() + 0.3) << key;
      }
      return;
    }
    default:
      FAIL() << "not one of the nuScenes-C goldens (the others: fast_ext_test.cpp, "
                "fast_mode_ext_spatial_test.cpp)";
  }
}

INSTANTIATE_TEST_SUITE_P(Manifest, FastGoldenTest, ::testing::ValuesIn(golden_case_ids()),
                         [](const ::testing::TestParamInfo<GoldenCase>& param_info) {
                           return pascal_case(param_info.param.name);
                         });

// Fog without injection: per-frame crop statistics of the fast field over 120 draws against numpy's
// fractal.
TEST(FastFogFieldTest, FrameStatisticsMatchReferenceFractalOverManyDraws) {
  const int rows = 90, cols = 160, draws = 120;
  for (int sev : {2, 5}) {
    const auto p = corruption::fog_params(sev);
    const int n = corruption::fog_map_size(rows, cols);
    double np_mean = 0, np_sd = 0, fast_mean = 0, fast_sd = 0, np_low = 0, fast_low = 0;
    for (int d = 0; d < draws; ++d) {
      rng::NumpyRandomState nr(static_cast<std::uint32_t>(500 + d));
      rng::FastRng fr(static_cast<std::uint64_t>(900 + d));
      cv::Mat a;
      corruption::plasma_fractal(n, p.decay, nr)(cv::Rect(0, 0, cols, rows)).convertTo(a, CV_32F);
      const cv::Mat b = corruption::fog_field_fast(rows, cols, p.decay, fr);
      cv::Scalar m, s;
      cv::meanStdDev(a, m, s);
      np_mean += m[0] / draws;
      np_sd += s[0] / draws;
      cv::meanStdDev(b, m, s);
      fast_mean += m[0] / draws;
      fast_sd += s[0] / draws;
      // Low-frequency energy: variance left after a 16x16 box average (coarse structure).
      cv::Mat la, lb;
      cv::resize(a, la, cv::Size(cols / 16, rows / 16), 0, 0, cv::INTER_AREA);
      cv::resize(b, lb, cv::Size(cols / 16, rows / 16), 0, 0, cv::INTER_AREA);
      cv::meanStdDev(la, m, s);
      np_low += s[0] / draws;
      cv::meanStdDev(lb, m, s);
      fast_low += s[0] / draws;
    }
    EXPECT_NEAR(fast_mean, np_mean, 0.05) << "sev " << sev;
    EXPECT_NEAR(fast_sd, np_sd, 0.2 * np_sd) << "sev " << sev;
    EXPECT_NEAR(fast_low, np_low, 0.2 * np_low) << "sev " << sev;
  }
}

// Free-running Motion Blur angle: uniform on [-45, 45] (Kolmogorov-Smirnov, 2000 draws, alpha ~
// 0.001).
TEST(FastMotionBlurTest, AngleIsUniformOnReferenceRange) {
  rng::FastRng rng(8);
  std::vector<double> a;
  for (int i = 0; i < 2000; ++i) a.push_back(rng.uniform(-45.0, 45.0));
  std::sort(a.begin(), a.end());
  double d = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double f = (a[i] + 45.0) / 90.0;
    d = std::max(
        {d, std::fabs(f - static_cast<double>(i) / a.size()), std::fabs(f - (i + 1.0) / a.size())});
  }
  EXPECT_LT(d, 1.95 / std::sqrt(2000.0));
}

}  // namespace
}  // namespace faultline::testing
