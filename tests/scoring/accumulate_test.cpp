// Hand-computed small tables: the spec §7 worked example, tie order, the numpy grid and interp
// rules, yaw, the bike-rack faces and the metric aggregation.
#include "scoring/accumulate.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "scoring/geometry.hpp"
#include "scoring/metrics.hpp"

namespace faultline::scoring {
namespace {

EvalBox make_box(double x, double y, double score, int match_sample = 0) {
  EvalBox b;
  b.translation = {x, y, 0.5};
  b.size = {2, 4, 1.5};
  b.rotation = {1, 0, 0, 0};
  b.velocity = {0, 0};
  b.score = score;
  b.cls = 0;
  b.attr = 5;  // vehicle.moving
  b.match_sample = match_sample;
  return b;
}

class AccumulateTest : public ::testing::Test {
 protected:
  void Gt(std::vector<EvalBox> boxes) {
    gt_.sample_tokens = {"s0"};
    gt_.boxes = {std::move(boxes)};
  }
  void Pred(std::vector<EvalBox> boxes) {
    pred_.sample_tokens = {"s0"};
    pred_.boxes = {std::move(boxes)};
  }
  MetricData Run(double th = 2.0) {
    auto r = accumulate(gt_, pred_, 0, th);
    EXPECT_TRUE(r.is_ok());
    return *r;
  }
  EvalBoxes gt_, pred_;
};

// npos = 2; processed TP(0.9), FP(0.8), TP(0.7): rec = [0.5, 0.5, 1], prec = [1, 0.5, 2/3].
TEST_F(AccumulateTest, WorkedExampleOfSpecSection7) {
  Gt({make_box(0, 0, -1), make_box(10, 0, -1)});
  Pred({make_box(0.1, 0, 0.9), make_box(50, 0, 0.8), make_box(10.2, 0, 0.7)});
  const MetricData md = Run();
  for (int i = 0; i < 50; ++i) {
    EXPECT_DOUBLE_EQ(md.precision[static_cast<std::size_t>(i)], 1.0) << i;
    EXPECT_DOUBLE_EQ(md.confidence[static_cast<std::size_t>(i)], 0.9) << i;
  }
  EXPECT_DOUBLE_EQ(md.precision[50], 0.5);   // last of the run of equal recalls
  EXPECT_DOUBLE_EQ(md.confidence[50], 0.8);  // the FP's score
  EXPECT_NEAR(md.precision[75], 0.5 + 0.5 * (2.0 / 3.0 - 0.5), 1e-12);
  EXPECT_NEAR(md.confidence[75], 0.75, 1e-12);
  EXPECT_NEAR(md.precision[100], 2.0 / 3.0, 1e-12);
  // trans_err: e1 = 0.1, e2 = 0.2, M = [0.1, 0.15]; at confidence 0.8 the midpoint.
  EXPECT_NEAR(md.tp[kTrans][0], 0.1, 1e-12);
  EXPECT_NEAR(md.tp[kTrans][50], 0.125, 1e-12);
  EXPECT_NEAR(md.tp[kTrans][100], 0.15, 1e-12);
  EXPECT_EQ(md.max_recall_ind(), 100);
  // AP: precision - 0.1 clipped, mean over indices 11..100, / 0.9.
  double sum = 0;
  for (int i = 11; i <= 100; ++i)
    sum += std::max(md.precision[static_cast<std::size_t>(i)] - 0.1, 0.0);
  EXPECT_NEAR(calc_ap(md), sum / 90 / 0.9, 1e-12);
}

TEST_F(AccumulateTest, EqualScoresAreProcessedLastInFileFirst) {
  Gt({make_box(0, 0, -1)});
  Pred({make_box(0.1, 0, 0.5), make_box(0.3, 0, 0.5)});
  const MetricData md = Run();
  // The second box (0.3 m away) is processed first and takes the only GT.
  EXPECT_NEAR(md.tp[kTrans][0], 0.3, 1e-12);
}

TEST_F(AccumulateTest, ThresholdIsStrict) {
  Gt({make_box(0, 0, -1)});
  Pred({make_box(2.0, 0, 0.5)});
  const MetricData md = Run(2.0);
  for (double p : md.precision) EXPECT_EQ(p, 0.0);  // no match -> no_predictions
  for (double e : md.tp[kTrans]) EXPECT_EQ(e, 1.0);
}

TEST_F(AccumulateTest, DistanceTieGoesToTheEarlierGt) {
  Gt({make_box(-1, 0, -1), make_box(1, 0, -1)});
  EvalBox p = make_box(0, 0, 0.9);
  p.attr = 6;  // only the first GT carries vehicle.parked
  auto g = gt_.boxes[0];
  g[0].attr = 6;
  g[1].attr = 7;
  gt_.boxes[0] = g;
  Pred({p});
  EXPECT_DOUBLE_EQ(Run().tp[kAttr][0], 0.0);
}

TEST_F(AccumulateTest, AllNanAttributeErrorsGiveOnes) {
  EvalBox g = make_box(0, 0, -1);
  g.attr = -1;
  Gt({g});
  Pred({make_box(0, 0, 0.9)});
  const MetricData md = Run();
  for (double v : md.tp[kAttr]) EXPECT_EQ(v, 1.0);
}

TEST_F(AccumulateTest, NoGtGivesNoPredictionsCurves) {
  Gt({});
  Pred({make_box(0, 0, 0.9)});
  const MetricData md = Run();
  EXPECT_EQ(calc_ap(md), 0.0);
  EXPECT_EQ(calc_tp(md, kScale), 1.0);
}

TEST(NumpyHelpersTest, RecallGridIsIStepNotIOver100) {
  EXPECT_EQ(recall_grid(35), 0.35000000000000003);
  EXPECT_GT(recall_grid(35), 0.35);
  EXPECT_EQ(recall_grid(100), 1.0);
  EXPECT_EQ(recall_grid(10), 0.1);
}

TEST(NumpyHelpersTest, InterpTakesLastOfEqualXsAndEndsRule) {
  const std::vector<double> xs = {0.5, 0.5, 1.0}, ys = {1.0, 0.5, 0.6};
  EXPECT_EQ(np_interp(0.5, xs, ys, 9, 7), 0.5);
  EXPECT_EQ(np_interp(0.2, xs, ys, 9, 7), 9);
  EXPECT_EQ(np_interp(1.0, xs, ys, 9, 7), 0.6);  // x == last is a hit, not "right"
  EXPECT_EQ(np_interp(1.5, xs, ys, 9, 7), 7);
  EXPECT_NEAR(np_interp(0.75, xs, ys, 9, 7), 0.55, 1e-15);
}

TEST(GeometryTest, YawUsesFullQuaternionNotHalfAngleShortcut) {
  // Pure yaw of 0.7 rad.
  EXPECT_NEAR(quaternion_yaw({std::cos(0.35), 0, 0, std::sin(0.35)}), 0.7, 1e-12);
  // Non-unit and negated quaternions give the same heading.
  EXPECT_NEAR(quaternion_yaw({-2 * std::cos(0.35), 0, 0, -2 * std::sin(0.35)}), 0.7, 1e-12);
  // Yaw 1.0 followed by a global pitch of 0.4: the x-axis heading is atan2(sin 1, cos 0.4 cos 1),
  // which the 2*atan2(z, w) shortcut misses.
  const double cy = std::cos(0.5), sy = std::sin(0.5), cp = std::cos(0.2), sp = std::sin(0.2);
  const std::array<double, 4> q = {cp * cy, sp * sy, sp * cy, cp * sy};
  EXPECT_NEAR(quaternion_yaw(q), std::atan2(std::sin(1.0), std::cos(0.4) * std::cos(1.0)), 1e-12);
  EXPECT_NE(quaternion_yaw(q), 2 * std::atan2(q[3], q[0]));
}

TEST(GeometryTest, BikeRackTestIsInclusiveAndThreeDimensional) {
  RackBox rack{{10, 20, 1}, {2, 4, 1}, {1, 0, 0, 0}};  // w 2, l 4, h 1, yaw 0
  EXPECT_TRUE(point_in_box(rack, {12, 20, 1}));        // exactly on the +x face
  EXPECT_TRUE(point_in_box(rack, {10, 21, 1.5}));      // corner edge
  EXPECT_FALSE(point_in_box(rack, {10, 20, 1.55}));    // above
  EXPECT_FALSE(point_in_box(rack, {12.01, 20, 1}));
}

TEST(GeometryTest, BarrierOrientationUsesPeriodPi) {
  EXPECT_NEAR(angle_diff(0.1, 0.1 + M_PI, M_PI), 0.0, 1e-12);
  EXPECT_NEAR(angle_diff(0.1, 0.1 + M_PI, 2 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(angle_diff(3.1, -3.1, 2 * M_PI), 2 * M_PI - 6.2, 1e-12);
}

TEST(MetricsTest, NdsCombinesMapAndClippedTpScores) {
  MetricDataList curves;
  for (auto& row : curves) {
    for (auto& md : row) md = MetricData::no_predictions();
  }
  const DetectionMetrics m = compute_metrics(curves);
  EXPECT_EQ(m.mean_ap, 0.0);
  EXPECT_EQ(m.tp_errors[kTrans], 1.0);
  EXPECT_EQ(m.tp_scores[kVel], 0.0);
  EXPECT_EQ(m.nd_score, 0.0);
  EXPECT_TRUE(std::isnan(m.label_tp_errors[kClassTrafficCone][kOrient]));
  EXPECT_TRUE(std::isnan(m.label_tp_errors[kClassBarrier][kAttr]));
  EXPECT_FALSE(std::isnan(m.label_tp_errors[kClassBarrier][kOrient]));
}

}  // namespace
}  // namespace faultline::scoring
