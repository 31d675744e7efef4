#include "codec/image_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgproc.hpp>

namespace faultline::codec {
namespace {

namespace fs = std::filesystem;

class ImageFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::temp_directory_path() / ("faultline-image-file-" + std::to_string(::getpid())))
               .string();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static cv::Mat pattern(int cols, int rows) {
    cv::Mat m(rows, cols, CV_8UC3);
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < cols; ++x) {
        m.at<cv::Vec3b>(y, x) =
            cv::Vec3b(static_cast<std::uint8_t>(x * 7), static_cast<std::uint8_t>(y * 5),
                      static_cast<std::uint8_t>((x + y) * 3));
      }
    }
    return m;
  }

  std::string dir_;
};

TEST_F(ImageFileTest, APngRoundTripsExactlyAndAJpegIsWrittenByTurboJpeg) {
  const cv::Mat image = pattern(64, 48);
  ASSERT_TRUE(write_image_file(dir_ + "/a.png", image, 95).is_ok());
  auto png = read_image_file(dir_ + "/a.png", false);
  ASSERT_TRUE(png.is_ok()) << png.status().to_string();
  EXPECT_EQ(cv::norm(png->bgr, image, cv::NORM_INF), 0.0);
  EXPECT_TRUE(png->warning.empty());

  ASSERT_TRUE(write_image_file(dir_ + "/b.JPEG", image, 90).is_ok());  // the extension in any case
  std::ifstream f(dir_ + "/b.JPEG", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  ASSERT_GE(bytes.size(), 2u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[0]), 0xFF);
  EXPECT_EQ(static_cast<unsigned char>(bytes[1]), 0xD8);
  auto jpeg = read_image_file(dir_ + "/b.JPEG", false);
  ASSERT_TRUE(jpeg.is_ok());
  EXPECT_EQ(jpeg->bgr.size(), image.size());
}

TEST_F(ImageFileTest, ATruncatedJpegIsAnErrorNamingTheFileUnlessPartialIsAllowed) {
  ASSERT_TRUE(write_image_file(dir_ + "/full.jpg", pattern(64, 48), 90).is_ok());
  std::ifstream in(dir_ + "/full.jpg", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir_ + "/cut.jpg", std::ios::binary) << bytes.substr(0, bytes.size() / 2);

  auto refused = read_image_file(dir_ + "/cut.jpg", false);
  ASSERT_FALSE(refused.is_ok());
  EXPECT_NE(refused.status().message().find("input image '" + dir_ + "/cut.jpg'"),
            std::string::npos)
      << refused.status().message();
  EXPECT_NE(refused.status().message().find("--allow-partial"), std::string::npos);

  auto partial = read_image_file(dir_ + "/cut.jpg", true);
  ASSERT_TRUE(partial.is_ok()) << partial.status().to_string();
  EXPECT_EQ(partial->bgr.size(), cv::Size(64, 48));
  EXPECT_NE(partial->warning.find("using the partial decode"), std::string::npos)
      << partial->warning;
}

TEST_F(ImageFileTest, ADirectoryGivesItsImagesInNameOrderAndNamesWhatIsWrong) {
  ASSERT_TRUE(write_image_file(dir_ + "/b.png", pattern(8, 4), 95).is_ok());
  ASSERT_TRUE(write_image_file(dir_ + "/a.JPG", pattern(16, 4), 95).is_ok());
  std::ofstream(dir_ + "/notes.txt") << "not an image\n";
  auto images = read_image_dir(dir_);
  ASSERT_TRUE(images.is_ok()) << images.status().to_string();
  ASSERT_EQ(images->size(), 2u);
  EXPECT_EQ((*images)[0].cols, 16);  // a.JPG before b.png
  EXPECT_EQ((*images)[1].cols, 8);

  std::ofstream(dir_ + "/c.png") << "garbage";
  auto bad = read_image_dir(dir_);
  ASSERT_FALSE(bad.is_ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(bad.status().message().find(dir_ + "/c.png"), std::string::npos);

  fs::create_directories(dir_ + "/empty");
  EXPECT_EQ(read_image_dir(dir_ + "/empty").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(read_image_dir(dir_ + "/missing").status().code(), StatusCode::kNotFound);
}

TEST_F(ImageFileTest, AnUnwritablePathIsAnIoErrorNamingIt) {
  const Status s = write_image_file(dir_ + "/no/such/dir/out.jpg", pattern(8, 8), 95);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(dir_ + "/no/such/dir/out.jpg"), std::string::npos);
  EXPECT_EQ(write_image_file(dir_ + "/no/such/dir/out.png", pattern(8, 8), 95).code(),
            StatusCode::kIoError);
}

}  // namespace
}  // namespace faultline::codec
