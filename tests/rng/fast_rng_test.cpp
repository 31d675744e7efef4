// FastRng: determinism per seed and first two moments of its uniform, normal and Poisson samplers.
#include "rng/fast_rng.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace faultline::rng {
namespace {

TEST(FastRngTest, SameSeedSameStreamDifferentSeedDifferentStream) {
  FastRng a(42), b(42), c(43);
  int differ = 0;
  for (int i = 0; i < 100; ++i) {
    const auto x = a.next_u64();
    EXPECT_EQ(x, b.next_u64());
    differ += x != c.next_u64();
  }
  EXPECT_GT(differ, 95);
}

TEST(FastRngTest, UniformMomentsAndRange) {
  FastRng rng(1);
  const int n = 200000;
  double sum = 0, sq = 0;
  for (int i = 0; i < n; ++i) {
    const double u = rng.random_sample();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    sq += u * u;
  }
  EXPECT_NEAR(sum / n, 0.5, 0.005);
  EXPECT_NEAR(sq / n - (sum / n) * (sum / n), 1.0 / 12, 0.002);
}

TEST(FastRngTest, NormalMomentsAndTail) {
  FastRng rng(2);
  const int n = 400000;
  double sum = 0, sq = 0;
  int beyond2 = 0;
  for (int i = 0; i < n; ++i) {
    const double z = rng.standard_normal();
    ASSERT_FALSE(std::isnan(z));
    sum += z;
    sq += z * z;
    beyond2 += std::fabs(z) > 2.0;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sq / n, 1.0, 0.01);
  EXPECT_NEAR(static_cast<double>(beyond2) / n, 0.0455, 0.002);  // two-sided tail beyond 2 sigma
}

class FastPoissonTest : public ::testing::TestWithParam<double> {};

TEST_P(FastPoissonTest, MeanAndVarianceEqualLambda) {
  const double lam = GetParam();
  FastRng rng(3);
  const int n = 100000;
  double sum = 0, sq = 0;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<double>(rng.poisson(lam));
    ASSERT_GE(k, 0.0);
    sum += k;
    sq += k * k;
  }
  const double mean = sum / n, var = sq / n - mean * mean;
  EXPECT_NEAR(mean, lam, 5 * std::sqrt(lam / n) + 1e-9);
  EXPECT_NEAR(var, lam, 0.05 * lam + 0.01);
}

INSTANTIATE_TEST_SUITE_P(Lambdas, FastPoissonTest,
                         ::testing::Values(0.5, 3.0, 9.99, 10.0, 25.0, 125.0));

}  // namespace
}  // namespace faultline::rng
