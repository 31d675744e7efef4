#include "stats/histogram.hpp"

#include <gtest/gtest.h>

namespace faultline::stats {
namespace {

TEST(RunningSummaryTest, MatchesHandComputedValues) {
  RunningSummary s;
  for (double v : {2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0}) s.add(v);
  const Summary r = s.summary();
  EXPECT_EQ(r.count, 8u);
  EXPECT_DOUBLE_EQ(r.mean, 5.0);
  EXPECT_DOUBLE_EQ(r.stddev, 2.0);
  EXPECT_DOUBLE_EQ(r.min, 2.0);
  EXPECT_DOUBLE_EQ(r.max, 9.0);
}

TEST(RunningSummaryTest, EmptyIsAllZero) {
  const Summary r = RunningSummary{}.summary();
  EXPECT_EQ(r.count, 0u);
  EXPECT_EQ(r.max, 0.0);
}

TEST(LogHistogramTest, PercentilesWithinOneBucketOfExact) {
  LogHistogram h;
  for (int i = 1; i <= 1000; ++i) h.add(i * 0.01);  // 0.01 .. 10.0 ms
  EXPECT_NEAR(h.percentile(0.50), 5.0, 5.0 * 0.02);
  EXPECT_NEAR(h.percentile(0.95), 9.5, 9.5 * 0.02);
  EXPECT_NEAR(h.percentile(0.99), 9.9, 9.9 * 0.02);
  EXPECT_DOUBLE_EQ(h.percentile(1.0), 10.0);  // clamped to the observed max
}

TEST(LogHistogramTest, SingleValueIsExact) {
  LogHistogram h;
  h.add(3.25);
  EXPECT_DOUBLE_EQ(h.percentile(0.5), 3.25);
  EXPECT_DOUBLE_EQ(h.percentile(0.99), 3.25);
}

TEST(LogHistogramTest, OutlierMovesOnlyTheTail) {
  LogHistogram h;
  for (int i = 0; i < 99; ++i) h.add(1.0);
  h.add(500.0);
  EXPECT_NEAR(h.percentile(0.5), 1.0, 0.02);
  EXPECT_NEAR(h.percentile(0.99), 1.0, 0.02);
  EXPECT_DOUBLE_EQ(h.percentile(1.0), 500.0);
}

}  // namespace
}  // namespace faultline::stats
