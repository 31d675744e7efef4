// LaneRng: determinism per seed, independent lanes, balanced bits; fill_normals: bodies agree,
// moments, tails.
#include "rng/lane_rng.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include "rng/fast_rng.hpp"

namespace faultline::rng {
namespace {

TEST(LaneRngTest, SameSeedSameValuesAndSeedingAdvancesTheSource) {
  FastRng a(42), b(42);
  LaneRng la(a), lb(b);
  EXPECT_EQ(a.next_u64(), b.next_u64());
  std::uint32_t va[16], vb[16];
  for (int step = 0; step < 100; ++step) {
    la.next_values(va);
    lb.next_values(vb);
    for (int j = 0; j < 16; ++j) ASSERT_EQ(va[j], vb[j]);
  }
  FastRng c(43);
  LaneRng lc(c);
  lc.next_values(vb);
  la.next_values(va);
  int same = 0;
  for (int j = 0; j < 16; ++j) same += va[j] == vb[j];
  EXPECT_EQ(same, 0);
}

TEST(LaneRngTest, LanesDifferAndBitsAreBalanced) {
  FastRng seed(1);
  LaneRng lanes(seed);
  std::uint32_t v[16];
  long long ones[32] = {};
  std::set<std::uint32_t> distinct;
  const int steps = 20000;
  for (int step = 0; step < steps; ++step) {
    lanes.next_values(v);
    for (int j = 0; j < 16; ++j) {
      distinct.insert(v[j]);
      for (int bit = 0; bit < 32; ++bit) ones[bit] += (v[j] >> bit) & 1u;
    }
  }
  EXPECT_GT(distinct.size(), static_cast<std::size_t>(steps * 16 - 100));
  const double n = steps * 16.0;  // per bit: mean n/2, sd sqrt(n)/2 = 283
  for (int bit = 0; bit < 32; ++bit)
    EXPECT_NEAR(static_cast<double>(ones[bit]), n / 2, 5 * 283) << bit;
}

TEST(LaneRngTest, FillNormalsBodiesAgreeAndConsumeTheSameDraws) {
  for (std::size_t n : {0, 1, 15, 16, 17, 100, 4099}) {
    FastRng sa(9), sb(9);
    LaneRng la(sa), lb(sb);
    std::vector<float> a(n), b(n);
    fill_normals(a.data(), n, 0.2, 0.3, la, sa, /*allow_simd=*/true);
    fill_normals(b.data(), n, 0.2, 0.3, lb, sb, /*allow_simd=*/false);
    EXPECT_EQ(a, b) << n;
    EXPECT_EQ(sa.next_u64(), sb.next_u64())
        << n;  // the same ziggurat rejections went to the slow path
  }
}

TEST(LaneRngTest, FillNormalsMomentsAndTail) {
  FastRng seed(4);
  LaneRng lanes(seed);
  const std::size_t n = 1 << 20;
  std::vector<float> v(n);
  fill_normals(v.data(), n, 0.55, 0.3, lanes, seed);
  double sum = 0, sq = 0;
  std::size_t beyond3 = 0;
  for (float x : v) {
    sum += x;
    sq += static_cast<double>(x) * x;
    beyond3 += std::fabs((x - 0.55) / 0.3) > 3.0;
  }
  const double mean = sum / n, var = sq / n - mean * mean;
  EXPECT_NEAR(mean, 0.55, 0.002);
  EXPECT_NEAR(std::sqrt(var), 0.3, 0.002);
  EXPECT_NEAR(static_cast<double>(beyond3) / n, 0.0026998, 0.0004);  // both tails beyond 3 sd
}

}  // namespace
}  // namespace faultline::rng
