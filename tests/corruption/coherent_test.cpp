// CoherentCorruptor: deterministic per seed, the fault persists between consecutive frames (far
// more similar than independent draws), and stays within the corruption's bounds.
#include "corruption/coherent.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "corruption/corrupt.hpp"
#include "corruption/fog.hpp"
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

// A seed reproduces a long sequence exactly (the state carried between frames included), and
// another seed gives another sequence.
TEST_P(CoherentTest, SeedReproducesALongSequenceAndAnotherSeedDiffers) {
  const cv::Mat frame = faultline::testing::scene(90, 160, 3);
  CoherentConfig cfg;
  cfg.type = GetParam();
  cfg.severity = 4;
  cfg.seed = 21;
  CoherentCorruptor a(cfg), b(cfg);
  cfg.seed = 22;
  CoherentCorruptor other(cfg);
  bool differs = false;
  for (int i = 0; i < 40; ++i) {
    const cv::Mat x = *a.apply(frame), y = *b.apply(frame), z = *other.apply(frame);
    ASSERT_EQ(cv::norm(x, y, cv::NORM_INF), 0.0) << "frame " << i;
    differs = differs || cv::norm(x, z, cv::NORM_INF) > 0.0;
  }
  // Deterministic corruptions and a constant tone curve cannot differ by seed.
  const bool seeded = cfg.type == Corruption::Fog || cfg.type == Corruption::Snow ||
                      cfg.type == Corruption::MotionBlur;
  if (seeded) {
    EXPECT_TRUE(differs);
  }
}

// Consecutive frames of a persistent fault agree far better than two independent fast-mode draws
// do.
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

INSTANTIATE_TEST_SUITE_P(MovingFaults, PersistenceTest,
                         ::testing::Values(Corruption::Fog, Corruption::MotionBlur));

// On a uniform frame the snow output is base + layer + rotated layer, so frame t+1 is frame t moved
// along the streak by the fall step, with wrap: the same flakes, fallen.
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
      moved.at<cv::Vec3b>(((y + dy) % f0.rows + f0.rows) % f0.rows,
                          ((x + dx) % f0.cols + f0.cols) % f0.cols) = f0.at<cv::Vec3b>(y, x);
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
  EXPECT_NEAR(m0, m1, 25.0);  // the same fog bank, moved
  EXPECT_LT(psnr(first, last), psnr(first, *CoherentCorruptor(cfg).apply(frame)));  // it did move
}

// The largest difference between 4-neighbours of the torus (wrapping): a bound on the field's
// change per low-res pixel, so the bilinear field changes by at most that / factor per upsampled
// pixel along either axis.
double MaxNeighbourStep(const cv::Mat& torus) {
  double d = 0;
  for (int y = 0; y < torus.rows; ++y) {
    for (int x = 0; x < torus.cols; ++x) {
      const float v = torus.at<float>(y, x);
      d = std::max(d, static_cast<double>(std::fabs(v - torus.at<float>(y, (x + 1) % torus.cols))));
      d = std::max(d, static_cast<double>(std::fabs(v - torus.at<float>((y + 1) % torus.rows, x))));
    }
  }
  return d;
}

// Wrap-aware difference of two offsets on a torus of `side` pixels, in (-side/2, side/2].
int TorusStep(int a, int b, int side) {
  int d = ((b - a) % side + side) % side;
  return d > side / 2 ? d - side : d;
}

// Each frame is the window of the drifting field at the frame's offset: fog_blend_fast over
// upsample_torus_window (the float32 field, cv::remap) within one level, at every offset phase and
// across the torus's wrap. Tiny frames (factor 1) as well.
TEST(CoherentFogTest, FrameIsTheFieldWindowAtItsOffsetWithinOneLevel) {
  for (const cv::Size size : {cv::Size(160, 90), cv::Size(30, 20)}) {
    const cv::Mat frame = faultline::testing::scene(size.height, size.width, 7);
    CoherentConfig cfg;
    cfg.type = Corruption::Fog;
    cfg.severity = 3;
    cfg.seed = 12;
    cfg.fog_drift_px =
        37.3;  // large steps: every phase of the quarter-resolution grid, and the wrap
    CoherentCorruptor c(cfg);
    double total = 0;
    for (int i = 0; i < 24; ++i) {
      const cv::Mat out = *c.apply(frame);
      const cv::Point o = c.fog_offset();
      const cv::Mat field =
          upsample_torus_window(c.fog_torus(), c.fog_factor(), o.y, o.x, frame.rows, frame.cols);
      const cv::Mat ref = fog_blend_fast(frame, field, fog_params(cfg.severity).strength);
      ASSERT_LE(cv::norm(out, ref, cv::NORM_INF), 1.0) << size << " frame " << i << " offset " << o;
      total += cv::norm(out, ref, cv::NORM_L1) / static_cast<double>(out.total() * 3);
    }
    EXPECT_LT(total / 24, 0.25) << size;  // off by one on a few values only
    EXPECT_EQ(c.fog_factor(), size.width > 32 ? 4 : 1);
  }
}

// The offset advances by the drift per frame (rounded to whole pixels, so never more than one pixel
// off the exact path), and the output changes between consecutive frames by no more than the field
// can change over that step.
TEST(CoherentFogTest, ConsecutiveFramesDifferByABoundedAmount) {
  const cv::Mat grey(90, 160, CV_8UC3, cv::Scalar::all(60));
  CoherentConfig cfg;
  cfg.type = Corruption::Fog;
  cfg.severity = 5;
  cfg.seed = 31;
  cfg.fog_drift_px = 2.5;
  CoherentCorruptor c(cfg);
  cv::Mat prev = *c.apply(grey);
  cv::Point at = c.fog_offset();
  const int side = c.fog_torus().rows * c.fog_factor();
  const double lipschitz = MaxNeighbourStep(c.fog_torus()) / c.fog_factor();
  const float m = 60.0f / 255.0f, a = static_cast<float>(fog_params(cfg.severity).strength);
  const double add_scale = a * 255.0f * (m / (m + a));
  double path_y = 0, path_x = 0;
  bool moved = false;
  for (int i = 1; i <= 60; ++i) {
    const cv::Mat next = *c.apply(grey);
    const cv::Point o = c.fog_offset();
    const int dy = TorusStep(at.y, o.y, side), dx = TorusStep(at.x, o.x, side);
    EXPECT_LE(std::hypot(dy, dx), cfg.fog_drift_px + 1.5) << "frame " << i;
    path_y += dy;
    path_x += dx;
    // trunc and the fixed-point rounding add up to 2 levels on top of the field's change.
    const double bound = add_scale * (std::abs(dy) + std::abs(dx)) * lipschitz + 2.0;
    EXPECT_LE(cv::norm(next, prev, cv::NORM_INF), bound) << "frame " << i;
    moved = moved || cv::norm(next, prev, cv::NORM_INF) > 0;
    prev = next;
    at = o;
  }
  EXPECT_NEAR(std::hypot(path_y, path_x), 60 * cfg.fog_drift_px,
              1.0);  // the rounding does not accumulate
  EXPECT_TRUE(moved);
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
