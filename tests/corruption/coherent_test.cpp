// CoherentCorruptor: deterministic per seed, the fault persists between consecutive frames (far more similar than
// independent draws), and stays within the corruption's bounds.
#include <gtest/gtest.h>

#include <cmath>

#include "corruption/coherent.hpp"
#include "corruption/corrupt.hpp"
#include "corruption/test_images.hpp"

namespace faultline::corruption {
namespace {

double psnr(const cv::Mat& a, const cv::Mat& b) {
  const double mse = cv::norm(a, b, cv::NORM_L2SQR) / static_cast<double>(a.total() * a.channels());
  return mse == 0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

class CoherentTest : public ::testing::TestWithParam<Corruption> {};

TEST_P(CoherentTest, SameSeedGivesSameSequence) {
  const cv::Mat frame = faultline::testing::scene(72, 128);
  CoherentConfig cfg;
  cfg.type = GetParam();
  cfg.severity = 3;
  cfg.seed = 17;
  CoherentCorruptor a(cfg), b(cfg);
  for (int i = 0; i < 4; ++i) {
    auto x = a.apply(frame);
    auto y = b.apply(frame);
    ASSERT_TRUE(x.is_ok() && y.is_ok());
    EXPECT_EQ(cv::norm(*x, *y, cv::NORM_INF), 0.0) << "frame " << i;
    EXPECT_EQ(x->size(), frame.size());
  }
  EXPECT_EQ(a.frames(), 4);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, CoherentTest, ::testing::ValuesIn(kAllCorruptions));

// Consecutive frames of a persistent fault agree far better than two independent fast-mode draws do.
class PersistenceTest : public ::testing::TestWithParam<Corruption> {};

TEST_P(PersistenceTest, ConsecutiveFramesAgreeMoreThanIndependentDraws) {
  const cv::Mat frame = faultline::testing::scene(90, 160);
  CoherentConfig cfg;
  cfg.type = GetParam();
  cfg.severity = 4;
  cfg.seed = 5;
  CoherentCorruptor c(cfg);
  const cv::Mat f0 = *c.apply(frame);
  const cv::Mat f1 = *c.apply(frame);
  rng::FastRng r1(100), r2(200);
  const cv::Mat i0 = *corrupt(frame, cfg.type, cfg.severity, r1);
  const cv::Mat i1 = *corrupt(frame, cfg.type, cfg.severity, r2);
  EXPECT_GT(psnr(f0, f1), psnr(i0, i1) + 3.0);
  EXPECT_GT(cv::norm(f0, f1, cv::NORM_INF), 0.0) << "the fault must still move";
}

INSTANTIATE_TEST_SUITE_P(MovingFaults, PersistenceTest, ::testing::Values(Corruption::Fog, Corruption::MotionBlur));

// On a uniform frame the snow output is base + layer + rotated layer, so frame t+1 is frame t moved along the
// streak by the fall step, with wrap: the same flakes, fallen.
TEST(CoherentSnowTest, NextFrameIsTheSameSnowMovedAlongItsStreak) {
  const cv::Mat grey(60, 90, CV_8UC3, cv::Scalar::all(60));
  CoherentConfig cfg;
  cfg.type = Corruption::Snow;
  cfg.severity = 2;
  cfg.seed = 4;
  cfg.snow_fall_px = 5.0;
  CoherentCorruptor c(cfg);
  const cv::Mat f0 = *c.apply(grey);
  const cv::Mat f1 = *c.apply(grey);
  const double rad = c.angle_deg() * M_PI / 180.0;
  const int dy = static_cast<int>(std::lround(-cfg.snow_fall_px * std::sin(rad)));
  const int dx = static_cast<int>(std::lround(-cfg.snow_fall_px * std::cos(rad)));
  ASSERT_GT(std::abs(dy) + std::abs(dx), 0);
  cv::Mat moved(f0.size(), f0.type());
  for (int y = 0; y < f0.rows; ++y) {
    for (int x = 0; x < f0.cols; ++x) {
      moved.at<cv::Vec3b>(((y + dy) % f0.rows + f0.rows) % f0.rows, ((x + dx) % f0.cols + f0.cols) % f0.cols) =
          f0.at<cv::Vec3b>(y, x);
    }
  }
  EXPECT_EQ(cv::norm(moved, f1, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(f0, f1, cv::NORM_INF), 0.0);
}

TEST(CoherentMotionBlurTest, AngleChangesSmoothlyAndStaysInRange) {
  const cv::Mat frame = faultline::testing::scene(32, 48);
  CoherentConfig cfg;
  cfg.type = Corruption::MotionBlur;
  cfg.severity = 2;
  cfg.seed = 3;
  cfg.angle_step_deg = 2.0;
  CoherentCorruptor c(cfg);
  double prev = 0;
  for (int i = 0; i < 300; ++i) {
    ASSERT_TRUE(c.apply(frame).is_ok());
    EXPECT_GE(c.angle_deg(), -45.0);
    EXPECT_LE(c.angle_deg(), 45.0);
    if (i > 0) {
      EXPECT_LT(std::fabs(c.angle_deg() - prev), 12.0) << "frame " << i;  // 6 sd of a 2-degree step
    }
    prev = c.angle_deg();
  }
}

TEST(CoherentFogTest, FieldDriftsAcrossFramesButKeepsItsLevel) {
  const cv::Mat frame = faultline::testing::scene(90, 160);
  CoherentConfig cfg;
  cfg.type = Corruption::Fog;
  cfg.severity = 5;
  cfg.seed = 9;
  CoherentCorruptor c(cfg);
  const cv::Mat first = *c.apply(frame);
  cv::Mat last;
  for (int i = 0; i < 30; ++i) last = *c.apply(frame);
  const double m0 = cv::mean(first.reshape(1))[0], m1 = cv::mean(last.reshape(1))[0];
  EXPECT_NEAR(m0, m1, 25.0);                       // the same fog bank, moved
  EXPECT_LT(psnr(first, last), psnr(first, *CoherentCorruptor(cfg).apply(frame)));  // it did move
}

TEST(CoherentTest, SizeChangeRestartsStateAndSeverityZeroIsIdentity) {
  CoherentConfig cfg;
  cfg.type = Corruption::Snow;
  cfg.severity = 0;
  CoherentCorruptor off(cfg);
  const cv::Mat frame = faultline::testing::scene(20, 30);
  EXPECT_EQ(cv::norm(*off.apply(frame), frame, cv::NORM_INF), 0.0);
  cfg.severity = 2;
  CoherentCorruptor c(cfg);
  EXPECT_TRUE(c.apply(frame).is_ok());
  auto bigger = c.apply(faultline::testing::scene(40, 60));
  ASSERT_TRUE(bigger.is_ok());
  EXPECT_EQ(bigger->size(), cv::Size(60, 40));
}

}  // namespace
}  // namespace faultline::corruption
