// RoboBEV mCE / mRR self-test against the paper's DETR3D table, plus table outputs.
#include <gtest/gtest.h>

#include <cmath>

#include "scoring/robustness.hpp"

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
      // The paper's per-corruption RRs come from 4-decimal averages; the exact form differs by <= 0.01.
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

}  // namespace
}  // namespace faultline::scoring
