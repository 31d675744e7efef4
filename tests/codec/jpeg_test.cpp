// TurboJPEG wrapper: round trips in BGR order, quality/subsampling options, and corrupt or
// truncated input handled as Status errors.
#include "codec/jpeg.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace faultline::codec {
namespace {

cv::Mat test_image() {
  cv::Mat img(90, 160, CV_8UC3, cv::Scalar(30, 60, 90));
  cv::rectangle(img, cv::Rect(20, 20, 60, 40), cv::Scalar(255, 0, 0),
                cv::FILLED);                                                   // pure blue in BGR
  cv::circle(img, cv::Point(120, 45), 25, cv::Scalar(0, 0, 255), cv::FILLED);  // pure red
  return img;
}

TEST(JpegTest, RoundTripKeepsSizeAndBgrOrder) {
  const cv::Mat img = test_image();
  auto bytes = encode_jpeg(img, 95);
  ASSERT_TRUE(bytes.is_ok()) << bytes.status().to_string();
  auto decoded = decode_jpeg(bytes->data(), bytes->size());
  ASSERT_TRUE(decoded.is_ok()) << decoded.status().to_string();
  ASSERT_EQ(decoded->size(), img.size());
  ASSERT_EQ(decoded->type(), CV_8UC3);
  const cv::Vec3b blue = decoded->at<cv::Vec3b>(40, 50);
  EXPECT_GT(blue[0], 200);
  EXPECT_LT(blue[2], 60);
  const cv::Vec3b red = decoded->at<cv::Vec3b>(45, 120);
  EXPECT_GT(red[2], 200);
  EXPECT_LT(red[0], 60);
  EXPECT_GT(cv::PSNR(*decoded, img), 25.0);  // saturated edges under 4:2:0 chroma
  auto size = jpeg_size(bytes->data(), bytes->size());
  ASSERT_TRUE(size.is_ok());
  EXPECT_EQ(*size, img.size());
}

TEST(JpegTest, LowerQualityAndFullChromaChangeSize) {
  const cv::Mat img = test_image();
  auto q95 = encode_jpeg(img, 95, Subsampling::k420);
  auto q30 = encode_jpeg(img, 30, Subsampling::k420);
  auto s444 = encode_jpeg(img, 95, Subsampling::k444);
  ASSERT_TRUE(q95.is_ok() && q30.is_ok() && s444.is_ok());
  EXPECT_LT(q30->size(), q95->size());
  EXPECT_GT(s444->size(), q95->size());
}

TEST(JpegTest, TruncatedJpegIsAStatusError) {
  auto bytes = encode_jpeg(test_image(), 95);
  ASSERT_TRUE(bytes.is_ok());
  for (std::size_t keep : {std::size_t{0}, std::size_t{10}, bytes->size() / 2, bytes->size() - 2}) {
    auto r = decode_jpeg(bytes->data(), keep);
    EXPECT_FALSE(r.is_ok()) << "kept " << keep;
  }
  EXPECT_EQ(decode_jpeg(bytes->data(), bytes->size() / 2).status().code(), StatusCode::kTruncated);
}

TEST(JpegTest, GarbageBytesAreCorruptData) {
  std::vector<std::uint8_t> junk(5000);
  for (std::size_t i = 0; i < junk.size(); ++i) junk[i] = static_cast<std::uint8_t>(i * 37 + 11);
  auto r = decode_jpeg(junk.data(), junk.size());
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_FALSE(decode_jpeg(nullptr, 0).is_ok());
}

TEST(JpegTest, FlippedBytesInsideTheScanNeverCrash) {
  auto bytes = encode_jpeg(test_image(), 90);
  ASSERT_TRUE(bytes.is_ok());
  for (std::size_t pos = 2; pos < bytes->size(); pos += 97) {
    auto copy = *bytes;
    copy[pos] ^= 0xA5;
    auto r = decode_jpeg(copy.data(),
                         copy.size());  // may succeed (damaged pixels) or fail; must not crash
    if (r.is_ok()) {
      EXPECT_EQ(r->type(), CV_8UC3);
    }
  }
}

TEST(JpegTest, BadEncodeArgumentsAreInvalidArgument) {
  EXPECT_EQ(encode_jpeg(cv::Mat(), 95).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(encode_jpeg(test_image(), 0).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(encode_jpeg(cv::Mat(4, 4, CV_32FC3), 95).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace faultline::codec
