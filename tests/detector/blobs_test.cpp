// find_blobs (one labelling pass over all classes) against find_blobs_per_class (one OpenCV
// connected-components pass per class): the same blobs, field by field, in the same order.
#include "detector/blobs.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "corruption/corrupt.hpp"
#include "dataset/synth_palette.hpp"
#include "dataset/synth_render.hpp"
#include "dataset/synth_world.hpp"
#include "detector/color_lut.hpp"
#include "detector/test_camera.hpp"
#include "rng/fast_rng.hpp"

namespace faultline::detector {
namespace {

using test_support::camera;

void expect_same_blobs(const cv::Mat& labels, double scale, const std::string& what,
                       const BlobConfig& config = {}) {
  const auto want = find_blobs_per_class(labels, scale, config);
  const auto got = find_blobs(labels, scale, config);
  ASSERT_EQ(got.size(), want.size()) << what;
  for (std::size_t i = 0; i < want.size(); ++i) {
    const Blob& a = got[i];
    const Blob& b = want[i];
    SCOPED_TRACE(what + " blob " + std::to_string(i));
    EXPECT_EQ(a.cls, b.cls);
    EXPECT_EQ(a.x0, b.x0);
    EXPECT_EQ(a.y0, b.y0);
    EXPECT_EQ(a.x1, b.x1);
    EXPECT_EQ(a.y1, b.y1);
    EXPECT_EQ(a.area_px, b.area_px);
    EXPECT_EQ(a.touches_left, b.touches_left);
    EXPECT_EQ(a.touches_right, b.touches_right);
    EXPECT_EQ(a.touches_top, b.touches_top);
    EXPECT_EQ(a.touches_bottom, b.touches_bottom);
    EXPECT_EQ(a.bottom_occluded, b.bottom_occluded);
  }
}

// Every blob, however small: exercises the component numbering on thousands of tiny components.
BlobConfig keep_all() {
  BlobConfig c;
  c.min_area_px = 0;
  c.min_side_px = 0;
  return c;
}

cv::Mat random_labels(int rows, int cols, int classes, double background, std::uint64_t seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::uniform_int_distribution<int> cls(0, classes - 1);
  cv::Mat labels(rows, cols, CV_8UC1);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      labels.at<std::uint8_t>(y, x) =
          u(gen) < background ? kNoClass : static_cast<std::uint8_t>(cls(gen));
  return labels;
}

TEST(BlobsTest, SynthFramesCleanAndCorruptedMatchPerClassReference) {
  std::mt19937_64 gen(7);
  const auto world = dataset::make_world(gen, 4.0);
  const ColorLut lut;
  rng::FastRng rng(11);
  const struct {
    corruption::Corruption type;
    int severity;
    double gain;  // the detector's low-light stretch, roughly
  } cases[] = {{corruption::Corruption::Dark, 0, 1.0}, {corruption::Corruption::Dark, 3, 1.0},
               {corruption::Corruption::Dark, 3, 3.0}, {corruption::Corruption::Dark, 5, 4.0},
               {corruption::Corruption::Snow, 3, 1.0}, {corruption::Corruption::Fog, 3, 1.0}};
  for (const double yaw : {0.0, 110.0}) {
    const cv::Mat frame = dataset::render_camera(world, 1.0, camera(yaw));
    for (const auto& k : cases) {
      auto corrupted = corruption::corrupt(frame, k.type, k.severity, rng);
      ASSERT_TRUE(corrupted.is_ok());
      cv::Mat img = *corrupted;
      if (k.gain != 1.0) img.convertTo(img, CV_8UC3, k.gain);
      for (const double scale : {1.0, 0.5, 0.25}) {
        cv::Mat in = img;
        if (scale != 1.0) cv::resize(img, in, cv::Size(), scale, scale, cv::INTER_AREA);
        const cv::Mat labels = lut.label_image(in);
        const std::string what = "yaw " + std::to_string(yaw) + " type " +
                                 std::to_string(static_cast<int>(k.type)) + " sev " +
                                 std::to_string(k.severity) + " gain " + std::to_string(k.gain) +
                                 " scale " + std::to_string(scale);
        expect_same_blobs(labels, scale, what);
        if (scale != 1.0) expect_same_blobs(labels, scale, what + " keep all", keep_all());
      }
    }
  }
}

TEST(BlobsTest, RandomLabelNoiseMatchesPerClassReference) {
  std::uint64_t seed = 1;
  for (const double background : {0.0, 0.3, 0.7, 0.95}) {
    for (const int classes : {1, 2, 3, dataset::kSynthClassCount}) {
      for (const auto& size : {cv::Size(1, 1), cv::Size(1, 37), cv::Size(41, 1), cv::Size(2, 2),
                               cv::Size(7, 5), cv::Size(64, 48), cv::Size(161, 91)}) {
        const cv::Mat labels = random_labels(size.height, size.width, classes, background, seed++);
        const std::string what = "bg " + std::to_string(background) + " classes " +
                                 std::to_string(classes) + " size " + std::to_string(size.width) +
                                 "x" + std::to_string(size.height);
        expect_same_blobs(labels, 1.0, what, keep_all());
        expect_same_blobs(labels, 0.5, what + " scale 0.5", keep_all());
        expect_same_blobs(labels, 0.25, what + " scale 0.25");
        BlobConfig small;
        small.min_area_px = 3;
        small.min_side_px = 2;
        expect_same_blobs(labels, 1.0, what + " small", small);
      }
    }
  }
}

TEST(BlobsTest, SinglePixelAndBorderComponents) {
  for (const int rows : {1, 2, 5, 6}) {
    for (const int cols : {1, 2, 5, 6}) {
      cv::Mat labels(rows, cols, CV_8UC1, cv::Scalar(kNoClass));
      // Corners, lone pixels of different classes, a diagonal chain that joins late.
      labels.at<std::uint8_t>(0, 0) = 1;
      labels.at<std::uint8_t>(rows - 1, cols - 1) = 1;
      labels.at<std::uint8_t>(0, cols - 1) = 2;
      labels.at<std::uint8_t>(rows - 1, 0) = 2;
      if (rows > 2 && cols > 2) labels.at<std::uint8_t>(rows / 2, cols / 2) = 3;
      expect_same_blobs(labels, 1.0, "corners " + std::to_string(cols) + "x" + std::to_string(rows),
                        keep_all());
    }
  }
  // Second row's left pixel comes before the first row's right pixel in OpenCV's numbering (same
  // 2x2 block row).
  cv::Mat labels(4, 8, CV_8UC1, cv::Scalar(kNoClass));
  labels.at<std::uint8_t>(0, 5) = 4;
  labels.at<std::uint8_t>(1, 0) = 4;
  labels.at<std::uint8_t>(0, 2) = 4;
  labels.at<std::uint8_t>(1, 3) = 5;
  labels.at<std::uint8_t>(3, 7) = 4;
  labels.at<std::uint8_t>(2, 7) = 4;
  expect_same_blobs(labels, 1.0, "block order", keep_all());
  // A U shape and a spiral-ish chain: components whose two arms meet only at the bottom.
  cv::Mat u(9, 9, CV_8UC1, cv::Scalar(kNoClass));
  for (int y = 0; y < 9; ++y) u.at<std::uint8_t>(y, 0) = u.at<std::uint8_t>(y, 8) = 6;
  for (int x = 0; x < 9; ++x) u.at<std::uint8_t>(8, x) = 6;
  u.at<std::uint8_t>(0, 4) = 6;
  u.at<std::uint8_t>(1, 3) = 6;
  u.at<std::uint8_t>(1, 5) = 7;
  expect_same_blobs(u, 1.0, "u shape", keep_all());
}

cv::Mat label_row(const std::vector<int>& values) {
  cv::Mat m(1, static_cast<int>(values.size()), CV_8UC1);
  for (std::size_t i = 0; i < values.size(); ++i)
    m.at<std::uint8_t>(0, static_cast<int>(i)) =
        values[i] < 0 ? kNoClass : static_cast<std::uint8_t>(values[i]);
  return m;
}

TEST(BlobsTest, BridgeLabelGapsFillsShortSameClassGapsOnly) {
  const int n = -1;
  cv::Mat row = label_row({1, n, n, n, 1, n, n, n, n, n, 1, n, 2, n, 2});
  bridge_label_gaps(row, 4);
  // 3 pixels between 1s: filled; 5: kept; 1 between 1 and 2: kept; 1 between 2s: filled.
  const cv::Mat want = label_row({1, 1, 1, 1, 1, n, n, n, n, n, 1, n, 2, 2, 2});
  EXPECT_EQ(cv::norm(row, want, cv::NORM_INF), 0.0);

  cv::Mat column = label_row({3, n, n, 3, n, n, n, n, n, 3}).t();
  column = column.clone();
  bridge_label_gaps(column, 4);
  const cv::Mat want_column = label_row({3, 3, 3, 3, n, n, n, n, n, 3}).t();
  EXPECT_EQ(cv::norm(column, want_column, cv::NORM_INF), 0.0);

  cv::Mat untouched = label_row({1, n, 1});
  bridge_label_gaps(untouched, 0);
  EXPECT_EQ(untouched.at<std::uint8_t>(0, 1), kNoClass);
}

}  // namespace
}  // namespace faultline::detector
