// The report is self-contained and actually renders: headless Chromium screenshots it and the PNG
// must show many colours and plenty of non-white pixels.
#include "report/report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "report/label_layout.hpp"

namespace faultline::report {
namespace {

ReportData sample_data() {
  ReportData data;
  auto base = scoring::detr3d_baseline();
  base.latency_ms = 120;
  scoring::DetectorScores other = base;
  other.name = "BEVDet-like";
  other.clean_nds = 0.47;
  other.latency_ms = 45;
  for (auto& c : other.corruptions) {
    for (double& v : c.nds_by_level) v = std::min(0.46, v * 1.15);
  }
  data.detectors.push_back(*scoring::compute_robustness(base, scoring::detr3d_baseline()));
  data.detectors.push_back(*scoring::compute_robustness(other, scoring::detr3d_baseline()));
  auto bench = parse_corrupt_bench(
      R"([{"type":"fog","level":3,"mode":"exact","ms":12.5,"psnr_db":31.2},
          {"type":"fog","level":3,"mode":"fast","ms":3.1,"psnr_db":27.9,"max_abs_diff":12},
          {"type":"snow","level":2,"mode":"exact","ms":40.2,"psnr_db":35.0}])",
      "mem");
  EXPECT_TRUE(bench.is_ok());
  data.corrupt_bench = *bench;
  data.variants = {{"temporal, scale 1", "clean", 0.58, 12.0},
                   {"temporal, scale 0.5", "clean", 0.45, 30.0},
                   {"single-frame, scale 1", "clean", 0.50, 60.0},
                   {"temporal, scale 1", "frame_lost/mid", 0.41, 12.0},
                   {"single-frame, scale 1", "frame_lost/mid", 0.30, 60.0}};
  return data;
}

TEST(ReportTest, HtmlIsSelfContainedWithAllViews) {
  const std::string html = render_html(sample_data());
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http://") == std::string::npos ||
                html.find("http://") == html.find("http://www.w3.org/2000/svg"),
            true);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  for (const char* view :
       {"NDS by corruption", "Per-corruption NDS by severity", "Clean NDS vs mCE",
        "Clean NDS vs mRR", "Detector latency vs clean NDS", "Corruption engine: time vs fidelity",
        "Detector fps vs clean NDS (input scales)", "Temporal vs single-frame: NDS by condition",
        "single-frame, scale 1 / frame_lost/mid: NDS 0.3000"}) {
    EXPECT_NE(html.find(view), std::string::npos) << view;
  }
  EXPECT_NE(html.find("70.77"), std::string::npos);  // DETR3D mRR in the summary table
}

// bench/results/corrupt.json names levels ("mid"); the table and the scatter show them as written
// (they showed 0).
TEST(ReportTest, CorruptionEngineShowsTheLevelsOfTheBenchFile) {
  auto bench = parse_corrupt_bench(
      R"([{"type":"fog","level":"mid","mode":"fast","ms":1.2,"psnr_db":97.0},
          {"type":"fog","level":"hard","mode":"numpy","ms":20.5,"psnr_db":99.0},
          {"type":"snow","level":3,"mode":"fast","ms":3.0,"psnr_db":60.0}])",
      "corrupt.json");
  ASSERT_TRUE(bench.is_ok()) << bench.status().message();
  EXPECT_EQ((*bench)[0].level, "mid");
  EXPECT_EQ((*bench)[2].level, "3");
  ReportData data;
  data.corrupt_bench = *bench;
  const std::string html = render_html(data);
  EXPECT_NE(html.find("<td>fog</td><td>mid</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>fog</td><td>hard</td>"), std::string::npos);
  EXPECT_NE(html.find(">fog/mid fast<"), std::string::npos);
  EXPECT_NE(html.find(">snow/3 fast<"), std::string::npos);
  EXPECT_EQ(html.find("fog/0"), std::string::npos);
}

// Points on top of each other (the engine chart's fast and numpy runs of one kernel often are):
// every label that is drawn has a place of its own inside the plot.
TEST(LabelLayoutTest, LabelsNeverOverlapAndStayInsideThePlot) {
  std::vector<LabelAnchor> anchors;
  for (int i = 0; i < 24; ++i) {
    anchors.push_back(
        {200.0 + (i % 3), 150.0 + (i % 2), "motion_blur/hard numpy " + std::to_string(i)});
  }
  anchors.push_back({480.0, 60.0, "far away"});
  const auto boxes = place_labels(anchors, 10, 6, 64, 40, 516, 324);
  ASSERT_EQ(boxes.size(), anchors.size());
  int drawn = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (!boxes[i]) continue;
    ++drawn;
    EXPECT_GE(boxes[i]->x, 64);
    EXPECT_LE(boxes[i]->x + boxes[i]->width, 516);
    EXPECT_GE(boxes[i]->y - boxes[i]->height, 40);
    EXPECT_LE(boxes[i]->y, 324);
    for (std::size_t j = 0; j < i; ++j) {
      if (boxes[j]) {
        EXPECT_FALSE(boxes[i]->overlaps(*boxes[j])) << i << " and " << j;
      }
    }
  }
  EXPECT_GE(drawn, 12);       // a crowd still gets most of its labels
  EXPECT_TRUE(boxes.back());  // a lone point always does
}

TEST(ReportTest, BadBenchFileIsRejectedWithPlace) {
  auto r = parse_corrupt_bench(R"([{"type":"fog"}])", "corrupt.json");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("corrupt.json[0]"), std::string::npos);
}

TEST(ReportTest, RendersInHeadlessChromium) {
  const char* chromium = "/usr/bin/chromium";
  if (!std::filesystem::exists(chromium))
    GTEST_SKIP() << "chromium not installed: render test skipped";
  const auto dir =
      std::filesystem::temp_directory_path() / ("faultline_report_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "profile");
  const auto html = dir / "report.html", png = dir / "shot.png";
  {
    std::ofstream out(html);
    out << render_html(sample_data());
  }
  const std::string cmd =
      std::string(chromium) +
      " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
      " --disable-background-networking --disable-component-update --disable-sync"
      " --user-data-dir=" +
      (dir / "profile").string() + " --screenshot=" + png.string() +
      " --window-size=1200,1600 file://" + html.string() + " > " + (dir / "log.txt").string() +
      " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const cv::Mat img = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << "no screenshot at " << png;
  std::set<int> colours;
  std::size_t non_white = 0;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const auto p = img.at<cv::Vec3b>(y, x);
      colours.insert((p[0] << 16) | (p[1] << 8) | p[2]);
      if (p[0] < 240 || p[1] < 240 || p[2] < 240) ++non_white;
    }
  }
  const double frac = static_cast<double>(non_white) / static_cast<double>(img.total());
  EXPECT_GT(colours.size(), 50u);
  EXPECT_GT(frac, 0.03) << "page looks blank";
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace faultline::report
