// zoom_blur's cascade step: held to a plain restatement of its documented arithmetic (so the vector
// path and the portable one, run by the scalar.* suites, give the same bytes), flat frames, and its
// distance from the float64 mean of the frame and its corner-aligned bilinear zoom.
#include "corruption/zoom_average.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <stdexcept>

namespace faultline::corruption {
namespace {

// One axis: output k (from the trim) samples the crop at k (n_in - 1) / (n_out - 1).
double coordinate(int k, int n_in, int n_out) {
  return n_out > 1 ? k * (static_cast<double>(n_in - 1) / (n_out - 1)) : 0.0;
}

// The sample pair and the second's weight in units of `one`, as documented: rounded, and a weight
// that rounds to `one` moves to the next sample.
void taps(double c, int n_in, int one, int& first, int& second, int& weight) {
  first = std::min(static_cast<int>(std::floor(c)), n_in - 1);
  weight = static_cast<int>(std::lround((c - first) * one));
  if (weight == one) {
    first = std::min(first + 1, n_in - 1);
    weight = 0;
  }
  second = std::min(first + 1, n_in - 1);
}

cv::Mat restated(const cv::Mat& in, const cv::Rect& crop, const cv::Size& scaled, int bias) {
  cv::Mat out(in.size(), CV_8UC3);
  const int trim_y = (scaled.height - in.rows) / 2, trim_x = (scaled.width - in.cols) / 2;
  for (int y = 0; y < in.rows; ++y) {
    int r0, r1, wy;
    taps(coordinate(y + trim_y, crop.height, scaled.height), crop.height, 1 << 15, r0, r1, wy);
    for (int x = 0; x < in.cols; ++x) {
      int c0, c1, wx;
      taps(coordinate(x + trim_x, crop.width, scaled.width), crop.width, 64, c0, c1, wx);
      for (int ch = 0; ch < 3; ++ch) {
        auto column = [&](int r) {
          const cv::Vec3b* row = in.ptr<cv::Vec3b>(crop.y + r);
          return row[crop.x + c0][ch] * (64 - wx) + row[crop.x + c1][ch] * wx;
        };
        const int h0 = column(r0), h1 = column(r1);
        const int layer = h0 + static_cast<int>(std::floor((h1 - h0) * wy / 32768.0 + 0.5));
        out.ptr<cv::Vec3b>(y)[x][ch] =
            static_cast<std::uint8_t>((64 * in.ptr<cv::Vec3b>(y)[x][ch] + layer + bias) / 128);
      }
    }
  }
  return out;
}

cv::Mat random_frame(int rows, int cols, int seed) {
  cv::Mat m(rows, cols, CV_8UC3);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  return m;
}

// A crop for zoom factor z as zoom_blur takes it: ceil(len / z) from the centre, scaled back to
// round(that * z).
struct ZoomCase {
  int rows, cols;
  double z;
};

void crop_for(const ZoomCase& c, cv::Rect& crop, cv::Size& scaled) {
  const int ch = static_cast<int>(std::ceil(c.rows / c.z));
  const int cw = static_cast<int>(std::ceil(c.cols / c.z));
  crop = cv::Rect((c.cols - cw) / 2, (c.rows - ch) / 2, cw, ch);
  scaled = cv::Size(static_cast<int>(std::nearbyint(cw * c.z)),
                    static_cast<int>(std::nearbyint(ch * c.z)));
}

class ZoomAverageTest : public ::testing::TestWithParam<ZoomCase> {};

TEST_P(ZoomAverageTest, GivesTheDocumentedArithmeticByteForByte) {
  const ZoomCase c = GetParam();
  cv::Rect crop;
  cv::Size scaled;
  crop_for(c, crop, scaled);
  const cv::Mat in = random_frame(c.rows, c.cols, c.rows * 7 + c.cols);
  for (const int bias : {0, 32, 96, 127}) {
    cv::Mat out;
    zoom_average(in, crop, scaled, bias, out);
    const cv::Mat want = restated(in, crop, scaled, bias);
    ASSERT_EQ(cv::norm(out, want, cv::NORM_INF), 0.0)
        << c.rows << "x" << c.cols << " z " << c.z << " bias " << bias;
  }
}

// Within a level of floor(the float64 mean + bias / 128), the layer being scipy's order-1 zoom, and
// off as often up as down.
TEST_P(ZoomAverageTest, IsWithinALevelOfTheExactMeanAndUnbiased) {
  const ZoomCase c = GetParam();
  cv::Rect crop;
  cv::Size scaled;
  crop_for(c, crop, scaled);
  const cv::Mat in = random_frame(c.rows, c.cols, c.cols);
  cv::Mat out;
  zoom_average(in, crop, scaled, 32, out);
  const int trim_y = (scaled.height - in.rows) / 2, trim_x = (scaled.width - in.cols) / 2;
  double signed_sum = 0;
  for (int y = 0; y < in.rows; ++y) {
    const double sy = coordinate(y + trim_y, crop.height, scaled.height);
    const int y0 = std::min(static_cast<int>(sy), crop.height - 1);
    const int y1 = std::min(y0 + 1, crop.height - 1);
    for (int x = 0; x < in.cols; ++x) {
      const double sx = coordinate(x + trim_x, crop.width, scaled.width);
      const int x0 = std::min(static_cast<int>(sx), crop.width - 1);
      const int x1 = std::min(x0 + 1, crop.width - 1);
      for (int ch = 0; ch < 3; ++ch) {
        auto at = [&](int r, int col) { return in.at<cv::Vec3b>(crop.y + r, crop.x + col)[ch]; };
        const double top = at(y0, x0) + (sx - x0) * (at(y0, x1) - at(y0, x0));
        const double bottom = at(y1, x0) + (sx - x0) * (at(y1, x1) - at(y1, x0));
        const double layer = top + (sy - y0) * (bottom - top);
        const double want = std::floor((in.at<cv::Vec3b>(y, x)[ch] + layer) / 2 + 32 / 128.0);
        const int got = out.at<cv::Vec3b>(y, x)[ch];
        ASSERT_LE(std::abs(got - want), 1) << y << "," << x << "," << ch;
        signed_sum += got - want;
      }
    }
  }
  // On noise (the worst case: neighbours up to 255 levels apart, so the 1/64-pixel column weights
  // move the layer by up to 2 levels) values are off by one often, but in both directions alike.
  const double bias = signed_sum / (static_cast<double>(in.total()) * 3);
  if (in.total() >= 1000) {
    EXPECT_LT(std::fabs(bias), 0.02);  // 0.002-0.007 measured
  }
}

INSTANTIATE_TEST_SUITE_P(Sizes, ZoomAverageTest,
                         ::testing::Values(ZoomCase{900, 1600, 1.3}, ZoomCase{900, 1600, 1.02},
                                           ZoomCase{197, 333, 1.11}, ZoomCase{31, 47, 1.25},
                                           ZoomCase{5, 7, 1.0}, ZoomCase{1, 1, 1.2},
                                           ZoomCase{2, 3, 1.3}, ZoomCase{17, 6, 1.05}));

TEST(ZoomAverageTest, FlatFrameKeepsItsValue) {
  for (const int v : {0, 1, 128, 254, 255}) {
    const cv::Mat in(90, 161, CV_8UC3, cv::Scalar::all(v));
    cv::Mat out;
    zoom_average(in, cv::Rect(10, 5, 140, 79), cv::Size(161, 91), 127, out);
    EXPECT_EQ(cv::countNonZero(out.reshape(1) != v), 0) << v;
  }
}

TEST(ZoomAverageTest, RefusesWhatItCannotDo) {
  const cv::Mat in(20, 30, CV_8UC3, cv::Scalar::all(9));
  cv::Mat out;
  const cv::Size scaled(30, 20);
  EXPECT_THROW(zoom_average(in, cv::Rect(25, 0, 10, 20), scaled, 0, out), std::invalid_argument);
  EXPECT_THROW(zoom_average(in, cv::Rect(0, 0, 30, 20), cv::Size(29, 20), 0, out),
               std::invalid_argument);
  EXPECT_THROW(zoom_average(in, cv::Rect(0, 0, 30, 20), scaled, 128, out), std::invalid_argument);
  EXPECT_THROW(zoom_average(cv::Mat(20, 30, CV_8UC1), cv::Rect(0, 0, 30, 20), scaled, 0, out),
               std::invalid_argument);
  cv::Mat same = in.clone();
  EXPECT_THROW(zoom_average(same, cv::Rect(0, 0, 30, 20), scaled, 0, same), std::invalid_argument);
}

}  // namespace
}  // namespace faultline::corruption
