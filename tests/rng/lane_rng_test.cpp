// LaneRng: determinism per seed, independent lanes, balanced bits.
#include <gtest/gtest.h>

#include <cstdint>
#include <set>

#include "rng/fast_rng.hpp"
#include "rng/lane_rng.hpp"

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
  for (int bit = 0; bit < 32; ++bit) EXPECT_NEAR(static_cast<double>(ones[bit]), n / 2, 5 * 283) << bit;
}

}  // namespace
}  // namespace faultline::rng
