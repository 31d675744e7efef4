// The benchmark's HTML report shows each corruption it ran: a small run's finish writes one inline
// JPEG per image corruption, each decodable and of the expected size.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "campaign/benchmark.hpp"
#include "codec/jpeg.hpp"
#include "faultline_tool.hpp"  // tests/

namespace faultline::campaign {
namespace {
namespace fs = std::filesystem;

// RFC 4648 decoding, independent of the report's encoder.
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

ConditionResult result(const std::string& condition, double nds) {
  ConditionResult r;
  r.condition = condition;
  r.seed = 1;
  r.ok = true;
  r.nds = nds;
  return r;
}

TEST(BenchmarkReportTest, ReportShowsOneThumbnailPerCorruptionItRan) {
  const fs::path dir =
      fs::temp_directory_path() / ("faultline_benchmark_report_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  BenchmarkOptions o;
  o.out_dir = dir.string();
  o.corruptions = {"fog", "low_light", "camera_crash"};
  o.levels = {"easy", "hard"};
  std::vector<ConditionResult> runs = {result("clean", 0.5)};
  for (const auto& c : o.corruptions) {
    for (const auto& l : o.levels) runs.push_back(result(c + "/" + l, 0.4));
  }
  ASSERT_TRUE(finish_benchmark(o, runs, stderr));
  const std::string html = test_tool::read_text(dir / "report.html");
  const std::string prefix = "data:image/jpeg;base64,";
  int pictures = 0;
  for (std::size_t at = html.find(prefix); at != std::string::npos;
       at = html.find(prefix, at + 1)) {
    const std::size_t begin = at + prefix.size(), end = html.find('"', begin);
    const auto jpeg = unbase64(html.substr(begin, end - begin));
    auto image = codec::decode_jpeg(jpeg.data(), jpeg.size());
    ASSERT_TRUE(image) << "picture " << pictures;
    // Two levels of 192 x 108 tiles (the 1600 x 900 frame scaled), 2 px apart.
    EXPECT_EQ(image->size(), cv::Size(2 * 192 + 2, 108));
    ++pictures;
  }
  EXPECT_EQ(pictures, 2);  // fog and low_light; camera_crash has no picture
  EXPECT_NE(html.find("low_light (dark): easy (2), hard (4)"), std::string::npos);
  EXPECT_NE(html.find("camera_crash: drops or damages whole frames"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace faultline::campaign
