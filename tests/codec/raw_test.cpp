// Raw frames into BGR: every layout gives the exact pixels, padding rows are skipped, bad sizes are
// refused.
#include "codec/raw.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace faultline::codec {
namespace {

TEST(RawToBgrTest, Bgr8WithRowPaddingIsCopiedExactly) {
  // 2x2 pixels, step 8 (2 padding bytes per row).
  const std::vector<std::uint8_t> bytes = {1, 2, 3, 4, 5, 6, 99, 99, 7, 8, 9, 10, 11, 12, 99, 99};
  auto bgr = raw_to_bgr("bgr8", 2, 2, 8, bytes.data(), bytes.size());
  ASSERT_TRUE(bgr.is_ok()) << bgr.status().message();
  ASSERT_EQ(bgr->type(), CV_8UC3);
  EXPECT_EQ(bgr->at<cv::Vec3b>(0, 0), cv::Vec3b(1, 2, 3));
  EXPECT_EQ(bgr->at<cv::Vec3b>(0, 1), cv::Vec3b(4, 5, 6));
  EXPECT_EQ(bgr->at<cv::Vec3b>(1, 0), cv::Vec3b(7, 8, 9));
  EXPECT_EQ(bgr->at<cv::Vec3b>(1, 1), cv::Vec3b(10, 11, 12));
  EXPECT_NE(bgr->data, bytes.data());  // a copy, never a view of the caller's bytes
}

TEST(RawToBgrTest, Rgb8IsSwappedAndMono8IsSpread) {
  const std::vector<std::uint8_t> rgb = {10, 20, 30, 40, 50, 60};
  auto a = raw_to_bgr("rgb8", 2, 1, 6, rgb.data(), rgb.size());
  ASSERT_TRUE(a.is_ok());
  EXPECT_EQ(a->at<cv::Vec3b>(0, 0), cv::Vec3b(30, 20, 10));
  EXPECT_EQ(a->at<cv::Vec3b>(0, 1), cv::Vec3b(60, 50, 40));
  const std::vector<std::uint8_t> mono = {7, 200, 0, 0};  // 2x1, step 4
  auto b = raw_to_bgr("mono8", 2, 1, 4, mono.data(), mono.size());
  ASSERT_TRUE(b.is_ok());
  EXPECT_EQ(b->at<cv::Vec3b>(0, 0), cv::Vec3b(7, 7, 7));
  EXPECT_EQ(b->at<cv::Vec3b>(0, 1), cv::Vec3b(200, 200, 200));
}

// The ROS 2 bridge's four-channel encodings: alpha dropped, rgba swapped; bytes past step x height
// (a ROS message may carry them) are ignored.
TEST(RawToBgrTest, FourChannelEncodingsDropAlphaAndTrailingBytesAreIgnored) {
  const std::vector<std::uint8_t> px = {1, 2, 3, 4, 0xEE};
  auto a = raw_to_bgr("bgra8", 1, 1, 4, px.data(), px.size());
  auto b = raw_to_bgr("rgba8", 1, 1, 4, px.data(), px.size());
  ASSERT_TRUE(a.is_ok() && b.is_ok()) << a.status().message() << b.status().message();
  EXPECT_EQ(a->at<cv::Vec3b>(0, 0), cv::Vec3b(1, 2, 3));
  EXPECT_EQ(b->at<cv::Vec3b>(0, 0), cv::Vec3b(3, 2, 1));
  EXPECT_TRUE(is_raw_encoding("rgba8"));
  EXPECT_FALSE(is_raw_encoding("mono16"));
}

// Grey in YUV (U = V = 128) stays grey; the two byte orders of yuv422 give the same picture.
TEST(RawToBgrTest, Yuv422InBothByteOrders) {
  const std::vector<std::uint8_t> uyvy = {128, 16, 128,
                                          235};  // 2x1: black (Y 16) and white (Y 235)
  const std::vector<std::uint8_t> yuyv = {16, 128, 235, 128};
  auto a = raw_to_bgr("yuv422", 2, 1, 4, uyvy.data(), uyvy.size());
  auto b = raw_to_bgr("yuv422_yuy2", 2, 1, 4, yuyv.data(), yuyv.size());
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  EXPECT_EQ(a->at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(a->at<cv::Vec3b>(0, 1), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(cv::norm(*a, *b, cv::NORM_INF), 0.0);
}

TEST(RawToBgrTest, WrongSizesAndEncodingsAreRefused) {
  const std::vector<std::uint8_t> bytes(12, 0);
  EXPECT_EQ(raw_to_bgr("bgr8", 2, 2, 6, bytes.data(), 11).status().code(),
            StatusCode::kCorruptData);
  EXPECT_EQ(raw_to_bgr("bgr8", 3, 2, 6, bytes.data(), 12).status().code(),
            StatusCode::kCorruptData);
  EXPECT_EQ(raw_to_bgr("bgr8", 0, 2, 6, bytes.data(), 12).status().code(),
            StatusCode::kCorruptData);
  EXPECT_EQ(raw_to_bgr("yuv420", 2, 2, 6, bytes.data(), 12).status().code(),
            StatusCode::kUnsupported);
  EXPECT_EQ(raw_to_bgr("yuv422", 3, 2, 6, bytes.data(), 12).status().code(),
            StatusCode::kCorruptData);
  EXPECT_EQ(raw_to_bgr("jpeg", 2, 2, 6, bytes.data(), 12).status().code(),
            StatusCode::kUnsupported);
}

}  // namespace
}  // namespace faultline::codec
