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
  ASSERT_TRUE(finish_benchmark(o, runs, {}));
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

// Progress goes to the caller's callback, never to the console: a finish without a clean run says
// why robustness is missing there, and a run's line reads as the benchmark prints it.
TEST(BenchmarkReportTest, FinishReportsMissingRobustnessToTheProgressCallback) {
  const fs::path dir =
      fs::temp_directory_path() / ("faultline_benchmark_noclean_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  BenchmarkOptions o;
  o.out_dir = dir.string();
  o.corruptions = {"fog"};
  o.levels = {"easy"};
  std::vector<std::string> lines;
  auto b = finish_benchmark(o, {result("fog/easy", 0.4)},
                            [&lines](const std::string& line) { lines.push_back(line); });
  ASSERT_TRUE(b) << b.status().message();
  EXPECT_EQ(lines,
            (std::vector<std::string>{"robustness not computed: the clean run did not complete"}));
  fs::remove_all(dir);
}

TEST(BenchmarkReportTest, RunLineShowsScoresOrTheFailure) {
  ConditionResult r = result("fog/easy", 0.41234);
  r.map = 0.3;
  r.wall_s = 12.34;
  EXPECT_EQ(run_line(1, 9, r, 70.4),
            "[2/9] fog/easy               seed 1  NDS 0.4123  mAP 0.3000  (12.3 s; ETA 70 s)");
  r.ok = false;
  r.error = "detector exited 3";
  EXPECT_EQ(run_line(1, 9, r), "[2/9] fog/easy               seed 1  FAILED: detector exited 3");
}

}  // namespace
}  // namespace faultline::campaign
