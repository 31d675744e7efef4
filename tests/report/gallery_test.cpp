// The corruption gallery and the report's thumbnails: one strip per corruption of the expected
// size, the same bytes for a seed, named errors, and one decodable inline JPEG per corruption in
// the HTML.
#include "report/gallery.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

#include "codec/jpeg.hpp"
#include "corruption/catalogue.hpp"
#include "dataset/synth_frame.hpp"
#include "report/report.hpp"

namespace faultline::report {
namespace {
namespace fs = std::filesystem;
using corruption::Corruption;

std::vector<std::uint8_t> read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// RFC 4648 decoding, written independently of the encoder under test.
std::vector<std::uint8_t> unbase64(const std::string& text) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<std::uint8_t> out;
  std::uint32_t bits = 0;
  int n = 0;
  for (char ch : text) {
    if (ch == '=') break;
    bits = (bits << 6) | static_cast<std::uint32_t>(alphabet.find(ch));
    n += 6;
    if (n >= 8) {
      n -= 8;
      out.push_back(static_cast<std::uint8_t>((bits >> n) & 0xFF));
    }
  }
  return out;
}

class GalleryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("faultline_gallery_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    // A small realistic frame keeps the 29 x 5 corruptions quick.
    frame_ = dataset::realistic_frame(320, 180, 0);
    options_.thumb_width = 64;
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
  cv::Mat frame_;
  GalleryOptions options_;
};

TEST_F(GalleryTest, WritesOneStripPerCorruptionOfTheExpectedSize) {
  std::vector<std::size_t> progress;
  auto entries =
      write_gallery((dir_ / "g").string(), frame_, options_,
                    [&](std::size_t i, std::size_t, Corruption) { progress.push_back(i); });
  ASSERT_TRUE(entries) << entries.status().message();
  const std::size_t n = std::size(corruption::kAllCorruptions);
  ASSERT_EQ(entries->size(), n);
  EXPECT_EQ(progress.size(), n);
  std::size_t jpgs = 0;
  for (const auto& f : fs::directory_iterator(dir_ / "g")) jpgs += f.path().extension() == ".jpg";
  EXPECT_EQ(jpgs, n);
  const std::string index = [&] {
    const auto b = read_bytes(dir_ / "g" / "index.md");
    return std::string(b.begin(), b.end());
  }();
  for (std::size_t i = 0; i < n; ++i) {
    const auto& e = (*entries)[i];
    EXPECT_EQ(e.type, corruption::kAllCorruptions[i]);
    const auto bytes = read_bytes(dir_ / "g" / e.file);
    EXPECT_EQ(bytes.size(), e.size_bytes) << e.file;
    auto image = codec::decode_jpeg(bytes.data(), bytes.size());
    ASSERT_TRUE(image) << e.file;
    // The frame and five severities, 64 x 36 each, 2 px apart.
    EXPECT_EQ(image->cols, 6 * 64 + 5 * 2) << e.file;
    EXPECT_EQ(image->rows, 36) << e.file;
    EXPECT_NE(index.find("](" + e.file + ")"), std::string::npos) << e.file;
    EXPECT_NE(index.find(corruption::severity_parameters(e.type, 5)), std::string::npos) << e.file;
  }
  EXPECT_NE(index.find("| impulse_noise | imagecorruptions 1.1.2 | statistical"),
            std::string::npos);
}

TEST_F(GalleryTest, SameSeedSameBytesAnotherSeedOtherNoise) {
  options_.types = {Corruption::GaussianNoise, Corruption::Fog, Corruption::RollingShutter};
  ASSERT_TRUE(write_gallery((dir_ / "a").string(), frame_, options_));
  ASSERT_TRUE(write_gallery((dir_ / "b").string(), frame_, options_));
  options_.seed = 7;
  ASSERT_TRUE(write_gallery((dir_ / "c").string(), frame_, options_));
  for (const char* f : {"gaussian_noise.jpg", "fog.jpg", "rolling_shutter.jpg", "index.md"}) {
    EXPECT_EQ(read_bytes(dir_ / "a" / f), read_bytes(dir_ / "b" / f)) << f;
  }
  EXPECT_NE(read_bytes(dir_ / "a" / "gaussian_noise.jpg"),
            read_bytes(dir_ / "c" / "gaussian_noise.jpg"));
  // rolling_shutter draws nothing: its strip does not depend on the seed.
  EXPECT_EQ(read_bytes(dir_ / "a" / "rolling_shutter.jpg"),
            read_bytes(dir_ / "c" / "rolling_shutter.jpg"));
}

TEST_F(GalleryTest, RollingShutterLeansAtTheGalleryYawRate) {
  auto still = gallery_tile(frame_, Corruption::RollingShutter, 0, options_);
  auto leaning = gallery_tile(frame_, Corruption::RollingShutter, 5, options_);
  ASSERT_TRUE(still && leaning);
  EXPECT_GT(cv::norm(*still, *leaning, cv::NORM_L1), 0.0);
}

TEST_F(GalleryTest, ErrorsNameTheProblem) {
  options_.thumb_width = 5;
  auto r = write_gallery((dir_ / "g").string(), frame_, options_);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("thumb width 5"), std::string::npos);
  options_.thumb_width = 64;
  fs::create_directories(dir_);
  std::ofstream(dir_ / "file") << "x";
  r = write_gallery((dir_ / "file" / "g").string(), frame_, options_);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find((dir_ / "file" / "g").string()), std::string::npos);
  auto t = gallery_tile(cv::Mat(), Corruption::Fog, 1, options_);
  ASSERT_FALSE(t);
  EXPECT_NE(t.status().message().find("gallery frame"), std::string::npos);
}

TEST_F(GalleryTest, BuiltInFrameIsTheRealistic1600x900Frame) {
  const cv::Mat f = gallery_frame();
  EXPECT_EQ(f.size(), cv::Size(1600, 900));
  EXPECT_EQ(cv::norm(f, dataset::realistic_frame(1600, 900, kGalleryFrameSeed), cv::NORM_INF), 0);
}

TEST(Base64Test, MatchesRfc4648Vectors) {
  const std::map<std::string, std::string> vectors = {{"", ""},
                                                      {"f", "Zg=="},
                                                      {"fo", "Zm8="},
                                                      {"foo", "Zm9v"},
                                                      {"foob", "Zm9vYg=="},
                                                      {"fooba", "Zm9vYmE="},
                                                      {"foobar", "Zm9vYmFy"}};
  for (const auto& [in, out] : vectors) {
    EXPECT_EQ(base64(std::vector<std::uint8_t>(in.begin(), in.end())), out) << in;
  }
}

// The benchmark report for fog, low_light and camera_crash at two levels: two pictures
// (camera_crash has none, and says why), each an inline JPEG of two tiles.
TEST_F(GalleryTest, ReportHasOneDecodableThumbnailPerImageCorruption) {
  ReportData data;
  data.thumbnails = corruption_thumbnails(
      {{"fog", "fog"}, {"low_light", "dark"}, {"camera_crash", "camera_crash"}}, {"easy", "hard"},
      frame_, options_);
  ASSERT_EQ(data.thumbnails.size(), 3u);
  EXPECT_TRUE(data.thumbnails[2].jpeg.empty());
  EXPECT_NE(data.thumbnails[1].caption.find("easy (2), hard (4)"), std::string::npos)
      << data.thumbnails[1].caption;
  const std::string html = render_html(data);
  const std::string prefix = "data:image/jpeg;base64,";
  int pictures = 0;
  for (std::size_t at = html.find(prefix); at != std::string::npos;
       at = html.find(prefix, at + 1)) {
    const std::size_t begin = at + prefix.size(), end = html.find('"', begin);
    const auto jpeg = unbase64(html.substr(begin, end - begin));
    auto image = codec::decode_jpeg(jpeg.data(), jpeg.size());
    ASSERT_TRUE(image) << "picture " << pictures;
    EXPECT_EQ(image->cols, 2 * 64 + 2);
    EXPECT_EQ(image->rows, 36);
    ++pictures;
  }
  EXPECT_EQ(pictures, 2);
  EXPECT_NE(html.find("camera_crash: drops or damages whole frames"), std::string::npos);
}

}  // namespace
}  // namespace faultline::report
