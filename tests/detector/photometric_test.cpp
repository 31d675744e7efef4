// normalise_photometric on frames whose answer is known: an affine haze is undone, over-exposed
// pixels are blacked out and counted, noise is measured and triggers the 2x2 average, and a clean
// frame keeps its colours.
#include "detector/photometric.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "dataset/synth_render.hpp"
#include "dataset/synth_world.hpp"
#include "detector/color_lut.hpp"
#include "detector/test_camera.hpp"

namespace faultline::detector {
namespace {

cv::Mat scene_frame() {
  std::mt19937_64 gen(7);
  const auto world = dataset::make_world(gen, 4.0);
  return dataset::render_camera(world, 1.0, test_support::camera(0));
}

// Fraction of the pixels the LUT classifies in `reference` that get the same class in `image`.
double same_class_fraction(const cv::Mat& reference, const cv::Mat& image) {
  const ColorLut lut;
  const cv::Mat a = lut.label_image(reference), b = lut.label_image(image);
  int labelled = 0, same = 0;
  for (int y = 0; y < a.rows; ++y)
    for (int x = 0; x < a.cols; ++x) {
      if (a.at<std::uint8_t>(y, x) == kNoClass) continue;
      ++labelled;
      same += a.at<std::uint8_t>(y, x) == b.at<std::uint8_t>(y, x);
    }
  EXPECT_GT(labelled, 1000);
  return labelled ? static_cast<double>(same) / labelled : 0.0;
}

TEST(PhotometricTest, CleanFrameKeepsItsClasses) {
  const cv::Mat frame = scene_frame();
  PhotometricStats stats;
  const cv::Mat out = normalise_photometric(frame, {}, &stats);
  EXPECT_EQ(stats.bin, 1);
  EXPECT_EQ(out.size(), frame.size());
  EXPECT_GT(same_class_fraction(frame, out), 0.97);
}

TEST(PhotometricTest, UniformHazeIsUndone) {
  const cv::Mat frame = scene_frame();
  cv::Mat hazy;
  frame.convertTo(hazy, CV_8UC3, 0.5, 100);  // half the light replaced by a grey airlight of 200
  EXPECT_LT(same_class_fraction(frame, hazy), 0.05) << "the haze must defeat the LUT on its own";
  PhotometricStats stats;
  const cv::Mat out = normalise_photometric(hazy, {}, &stats);
  EXPECT_GT(stats.black, 90);
  EXPECT_GT(stats.gain, 1.5);
  EXPECT_GT(same_class_fraction(frame, out), 0.85);
}

TEST(PhotometricTest, DisabledIsIdentity) {
  const cv::Mat frame = scene_frame();
  PhotometricConfig off;
  off.enabled = false;
  const cv::Mat out = normalise_photometric(frame, off);
  EXPECT_EQ(cv::norm(out, frame, cv::NORM_INF), 0.0);
}

TEST(PhotometricTest, OverExposedPixelsAreBlackedOutAndCounted) {
  cv::Mat frame(100, 200, CV_8UC3, cv::Scalar(60, 80, 100));
  frame(cv::Rect(0, 0, 50, 40)).setTo(cv::Scalar(30, 30, 255));  // red channel clipped: 2000 pixels
  frame(cv::Rect(100, 50, 10, 10)).setTo(cv::Scalar(253, 0, 0));  // at the clip level: 100 pixels
  frame(cv::Rect(150, 50, 10, 10)).setTo(cv::Scalar(0, 252, 0));  // just below: kept
  PhotometricStats stats;
  const cv::Mat out = normalise_photometric(frame, {}, &stats);
  ASSERT_EQ(out.size(), frame.size());
  EXPECT_DOUBLE_EQ(stats.clipped_fraction, 2100.0 / 20000.0);
  EXPECT_EQ(out.at<cv::Vec3b>(10, 10), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(out.at<cv::Vec3b>(55, 105), cv::Vec3b(0, 0, 0));
  EXPECT_NE(out.at<cv::Vec3b>(55, 155), cv::Vec3b(0, 0, 0));
}

TEST(PhotometricTest, NoiseIsMeasuredAndANoisyDarkFrameIsAveraged) {
  cv::Mat frame(400, 600, CV_8UC3, cv::Scalar(40, 40, 40));
  frame(cv::Rect(0, 0, 600, 100)).setTo(cv::Scalar(50, 50, 50));
  EXPECT_EQ(estimate_noise_sigma(frame), 0.0);
  cv::Mat noise(frame.size(), CV_32FC3);
  cv::randn(noise, 0.0, 4.0);
  cv::Mat noisy;
  frame.convertTo(noisy, CV_32FC3);
  noisy += noise;
  noisy.convertTo(noisy, CV_8UC3);
  EXPECT_NEAR(estimate_noise_sigma(noisy), 4.0, 0.6);
  PhotometricStats stats;
  const cv::Mat out =
      normalise_photometric(noisy, {}, &stats);  // the stretch (> 3x) lifts sigma past the limit
  EXPECT_GT(stats.gain, 3.0);
  EXPECT_EQ(stats.bin, 2);
  EXPECT_EQ(out.size(), cv::Size(300, 200));
}

}  // namespace
}  // namespace faultline::detector
