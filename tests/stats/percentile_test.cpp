// stats::percentile and stats::median against hand-computed values, in both interpolations.
#include "stats/percentile.hpp"

#include <gtest/gtest.h>

namespace faultline::stats {
namespace {

struct PercentileRow {
  std::vector<double> values;
  double q;
  double linear, nearest_half_up;
};

class PercentileTest : public ::testing::TestWithParam<PercentileRow> {};

TEST_P(PercentileTest, MatchesTable) {
  const auto& row = GetParam();
  EXPECT_DOUBLE_EQ(percentile(row.values, row.q), row.linear);
  EXPECT_DOUBLE_EQ(percentile(row.values, row.q, Interpolation::NearestHalfUp),
                   row.nearest_half_up);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, PercentileTest,
    ::testing::Values(
        PercentileRow{{}, 0.5, 0, 0}, PercentileRow{{3}, 0.99, 3, 3},
        PercentileRow{{5, 1, 3}, 0.5, 3, 3},       // odd count: the middle value either way
        PercentileRow{{4, 1, 3, 2}, 0.5, 2.5, 3},  // even count: mean or upper of the middle two
        PercentileRow{{4, 1, 3, 2}, 0.0, 1, 1}, PercentileRow{{4, 1, 3, 2}, 1.0, 4, 4},
        PercentileRow{{4, 1, 3, 2}, 0.25, 1.75, 2},           // position 0.75
        PercentileRow{{10, 20, 30, 40, 50}, 0.99, 49.6, 50},  // position 3.96
        PercentileRow{{4, 1, 3, 2}, 1.5, 4, 4}));             // q clamped to [0, 1]

TEST(MedianTest, IsThePercentileAtOneHalfAndKeepsTheCallersOrder) {
  const std::vector<double> v = {0.3, 0.1, 0.4, 0.2};
  EXPECT_DOUBLE_EQ(median(v), (0.2 + 0.3) / 2);
  EXPECT_DOUBLE_EQ(median(v, Interpolation::NearestHalfUp), 0.3);
  EXPECT_EQ(v, (std::vector<double>{0.3, 0.1, 0.4, 0.2}));
}

}  // namespace
}  // namespace faultline::stats
