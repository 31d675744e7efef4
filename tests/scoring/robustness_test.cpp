// RoboBEV mCE / mRR self-test against the paper's DETR3D table, plus table outputs.
#include "scoring/robustness.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "scoring/run_manifest.hpp"
#include "test_util.hpp"

namespace faultline::scoring {
namespace {

double round2(double fraction) { return std::round(fraction * 10000.0) / 100.0; }

TEST(RobustnessTest, Detr3dBaselineGivesPaperFigures) {
  for (bool rounded : {false, true}) {
    RobustnessOptions opts;
    opts.round_mean_nds_4dp = rounded;
    auto r = compute_robustness(detr3d_baseline(), detr3d_baseline(), opts);
    ASSERT_TRUE(r.is_ok());
    EXPECT_DOUBLE_EQ(round2(r->mce), 100.00);
    EXPECT_DOUBLE_EQ(round2(r->mrr), 70.77);
    const double paper_rr[] = {67.68, 61.65, 75.21, 63.00, 94.74, 65.96, 92.61, 45.29};
    ASSERT_EQ(r->corruptions.size(), 8u);
    for (std::size_t i = 0; i < 8; ++i) {
      // The paper's per-corruption RRs come from 4-decimal averages; the exact form differs by <=
      // 0.01.
      EXPECT_NEAR(round2(r->corruptions[i].rr), paper_rr[i], rounded ? 1e-9 : 0.0100001)
          << r->corruptions[i].name;
      EXPECT_DOUBLE_EQ(r->corruptions[i].ce, 1.0);
    }
  }
}

TEST(RobustnessTest, CeIsRatioOfSummedErrorsAndRrUsesOwnClean) {
  DetectorScores base{"base", 0.5, {{"fog", {0.4, 0.3, 0.2}}}};
  DetectorScores model{"model", 0.6, {{"fog", {0.5, 0.5, 0.2}}}};
  RobustnessOptions exact;
  exact.round_mean_nds_4dp = false;
  auto r = compute_robustness(model, base, exact);
  ASSERT_TRUE(r.is_ok());
  EXPECT_NEAR(r->corruptions[0].ce, (0.5 + 0.5 + 0.8) / (0.6 + 0.7 + 0.8), 1e-15);
  EXPECT_NEAR(r->corruptions[0].rr, 1.2 / (3 * 0.6), 1e-15);
  EXPECT_NEAR(r->mce, r->corruptions[0].ce, 0);
}

TEST(RobustnessTest, UnknownCorruptionHasNoCeAndLevelMismatchFails) {
  DetectorScores model{"m", 0.5, {{"fog", {0.4, 0.4, 0.4}}, {"dropout", {0.3, 0.3, 0.3}}}};
  auto r = compute_robustness(model, detr3d_baseline());
  ASSERT_TRUE(r.is_ok());
  EXPECT_TRUE(std::isnan(r->corruptions[1].ce));
  EXPECT_NEAR(r->mce, r->corruptions[0].ce, 0);
  DetectorScores two{"m", 0.5, {{"fog", {0.4, 0.4}}}};
  auto bad = compute_robustness(two, detr3d_baseline());
  ASSERT_FALSE(bad.is_ok());
  EXPECT_NE(bad.status().message().find("fog"), std::string::npos);
}

// RoboDrive's suite runs "dark"; the DETR3D baseline table calls it "low_light".
TEST(RobustnessTest, DarkIsScoredAgainstTheBaselinesLowLight) {
  DetectorScores dark{"m", 0.5, {{"dark", {0.3, 0.25, 0.2}}}};
  DetectorScores low_light{"m", 0.5, {{"low_light", {0.3, 0.25, 0.2}}}};
  auto a = compute_robustness(dark, detr3d_baseline());
  auto b = compute_robustness(low_light, detr3d_baseline());
  ASSERT_TRUE(a.is_ok());
  ASSERT_TRUE(b.is_ok());
  ASSERT_FALSE(std::isnan(a->corruptions[0].ce));
  EXPECT_DOUBLE_EQ(a->corruptions[0].ce, b->corruptions[0].ce);
  EXPECT_EQ(a->corruptions[0].name, "dark");
}

TEST(RobustnessTest, TablesNameTheLevelsThatWereRun) {
  DetectorScores model = detr3d_baseline();
  DetectorScores base = detr3d_baseline();
  for (auto* d : {&model, &base}) {
    for (auto& c : d->corruptions) c.nds_by_level = {c.nds_by_level[1]};  // mid only
  }
  auto r = compute_robustness(model, base);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  r->level_names = {"mid"};
  EXPECT_NE(robustness_markdown(*r).find("| corruption | mid |"), std::string::npos)
      << robustness_markdown(*r);
  EXPECT_EQ(robustness_markdown(*r).find("easy"), std::string::npos);
  EXPECT_NE(robustness_csv(*r).find(",fog,mid,"), std::string::npos);
  const std::string js = robustness_json(*r);
  const auto levels_at = js.find("\"levels\"");
  ASSERT_NE(levels_at, std::string::npos) << js;
  EXPECT_EQ(js.find("\"mid\"", levels_at), js.find('"', js.find('[', levels_at))) << js;
  r->level_names.clear();
  EXPECT_NE(robustness_markdown(*r).find("| corruption | easy |"), std::string::npos);
}

TEST(RobustnessTest, CanonicalNamesAndLevels) {
  EXPECT_EQ(canonical_corruption("MotionBlur"), "motion_blur");
  EXPECT_EQ(canonical_corruption("Camera Crash"), "camera_crash");
  EXPECT_EQ(canonical_corruption("low-light"), "low_light");
  EXPECT_EQ(severity_index("mid"), 1);
  EXPECT_EQ(severity_index("HARD"), 2);
  EXPECT_EQ(severity_index("extreme"), -1);
}

TEST(RobustnessTest, JsonRoundTripsAndTablesCarryThePercentages) {
  auto r = compute_robustness(detr3d_baseline(), detr3d_baseline());
  ASSERT_TRUE(r.is_ok());
  auto back = parse_robustness_json(robustness_json(*r), "mem");
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(back->detector, "DETR3D");
  EXPECT_DOUBLE_EQ(back->mrr, r->mrr);
  EXPECT_EQ(back->corruptions.size(), 8u);
  EXPECT_NE(robustness_markdown(*r).find("mRR 70.77 %"), std::string::npos);
  EXPECT_NE(robustness_csv(*r).find("DETR3D,snow,hard,0.1616"), std::string::npos);
}

// A mid-only benchmark's robustness.json keeps its level names through the report's reader (it
// showed "easy").
TEST(RobustnessTest, JsonKeepsTheLevelNamesOfAReducedMatrix) {
  DetectorScores mid_only = detr3d_baseline();
  for (auto& c : mid_only.corruptions) c.nds_by_level = {c.nds_by_level[1]};
  auto r = compute_robustness(mid_only, mid_only);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  r->level_names = {"mid"};
  auto back = parse_robustness_json(robustness_json(*r), "mem");
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(back->level_names, std::vector<std::string>{"mid"});
  EXPECT_EQ(level_name(*back, 0), "mid");
  EXPECT_NE(robustness_csv(*back).find("DETR3D,snow,mid,"), std::string::npos)
      << robustness_csv(*back);
}

// Scored run folders of the DETR3D table + a YAML manifest reproduce the paper's figures end to
// end.
TEST(RunManifestTest, ManifestOfScoredRunsGivesPaperFigures) {
  testing::TempDir dir("manifest");
  const DetectorScores table = detr3d_baseline();
  std::string yaml = "detector: detr3d-runs\nlatency_ms: 120\nruns:\n  clean: clean\n";
  auto write_run = [&](const std::string& sub, double nds) {
    std::filesystem::create_directories(dir.file(sub));
    testing::write_text(
        dir.file(sub) + "/metrics_summary.json",
        "{\"mean_ap\": 0.3, \"nd_score\": " + std::to_string(nds) + ", \"x\": NaN}");
  };
  write_run("clean", table.clean_nds);
  for (const auto& c : table.corruptions) {
    for (std::size_t l = 0; l < 3; ++l) {
      const std::string sub = c.name + "_" + kSeverityLevels[l];
      write_run(sub, c.nds_by_level[l]);
      yaml += "  " + c.name + "/" + kSeverityLevels[l] + ": " + sub + "\n";
    }
  }
  testing::write_text(dir.file("runs.yaml"), yaml);
  std::string name;
  double latency = -1;
  auto runs = read_run_manifest(dir.file("runs.yaml"), &name, &latency);
  ASSERT_TRUE(runs.is_ok()) << runs.status().message();
  EXPECT_EQ(name, "detr3d-runs");
  EXPECT_EQ(latency, 120);
  auto scores = collect_detector_scores(name, *runs);
  ASSERT_TRUE(scores.is_ok()) << scores.status().message();
  auto r = compute_robustness(*scores, detr3d_baseline());
  ASSERT_TRUE(r.is_ok());
  EXPECT_DOUBLE_EQ(round2(r->mce), 100.00);
  EXPECT_DOUBLE_EQ(round2(r->mrr), 70.77);
}

TEST(RunManifestTest, ConditionsFromFolderNamesAndMissingRuns) {
  EXPECT_EQ(condition_from_path("/x/runs/fog_easy"), "fog/easy");
  EXPECT_EQ(condition_from_path("/x/runs/MotionBlur/hard/"), "MotionBlur/hard");
  EXPECT_EQ(condition_from_path("/x/runs/clean"), "clean");
  auto missing = collect_detector_scores("d", {{"clean", "/nonexistent/run"}});
  ASSERT_FALSE(missing.is_ok());
  EXPECT_NE(missing.status().message().find("/nonexistent/run/metrics_summary.json"),
            std::string::npos);
}

}  // namespace
}  // namespace faultline::scoring
