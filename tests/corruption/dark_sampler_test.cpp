// Dark fast-mode sampling loop: the AVX2 and scalar bodies agree byte for byte, and the sampled
// frequencies follow the alias tables.
#include "corruption/dark_sampler.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "rng/fast_rng.hpp"
#include "rng/lane_rng.hpp"

namespace faultline::corruption {
namespace {

// Random packed alias entries for levels lo..hi (thresholds anywhere in 0..2^23).
std::vector<std::uint32_t> random_tables(int levels, rng::FastRng& rng) {
  std::vector<std::uint32_t> t(static_cast<std::size_t>(levels) * 256);
  for (auto& e : t) {
    const std::uint32_t threshold = rng.next_u32() % ((1u << kDarkAliasThresholdBits) + 1u);
    e = (threshold << 8) | (rng.next_u32() & 0xFFu);
  }
  return t;
}

TEST(DarkSamplerTest, SimdAndScalarBodiesGiveTheSameBytesAndState) {
  rng::FastRng setup(3);
  const int lo = 17, hi = 80;
  const auto tables = random_tables(hi - lo + 1, setup);
  for (std::size_t n : {0, 1, 15, 16, 17, 31, 32, 33, 64, 1000, 4099}) {
    std::vector<std::uint8_t> src(n), a(n), b(n);
    for (auto& v : src)
      v = static_cast<std::uint8_t>(lo + static_cast<int>(setup.next_u32() % (hi - lo + 1)));
    rng::FastRng seed_a(11), seed_b(11);
    rng::LaneRng ra(seed_a), rb(seed_b);
    dark_sample(tables.data(), lo, src.data(), a.data(), n, ra, /*allow_simd=*/true);
    dark_sample(tables.data(), lo, src.data(), b.data(), n, rb, /*allow_simd=*/false);
    EXPECT_EQ(a, b) << n;
    std::uint32_t va[16], vb[16];
    ra.next_values(va);
    rb.next_values(vb);
    EXPECT_EQ(std::vector<std::uint32_t>(va, va + 16), std::vector<std::uint32_t>(vb, vb + 16))
        << n;
  }
}

TEST(DarkSamplerTest, FrequenciesFollowTheAliasTable) {
  // One level: bucket j keeps j with probability 1/2 and otherwise gives (j + 1) % 256, so every
  // outcome has probability 1/256 overall and odd buckets are never special.
  std::vector<std::uint32_t> table(256);
  for (std::uint32_t j = 0; j < 256; ++j)
    table[j] = ((1u << (kDarkAliasThresholdBits - 1)) << 8) | ((j + 1) & 0xFFu);
  const std::size_t n = 256 * 4000;
  std::vector<std::uint8_t> src(n, 9), out(n);
  rng::FastRng seed(5);
  rng::LaneRng lanes(seed);
  dark_sample(table.data(), 9, src.data(), out.data(), n, lanes);
  std::vector<int> count(256);
  for (std::uint8_t v : out) ++count[v];
  for (int j = 0; j < 256; ++j) EXPECT_NEAR(count[static_cast<std::size_t>(j)], 4000, 5 * 63) << j;
}

TEST(DarkSamplerTest, MinMaxOverAllBytes) {
  std::vector<std::uint8_t> v(1001, 100);
  v[0] = 7;
  v[1000] = 201;
  EXPECT_EQ(dark_min_max(v.data(), v.size()), std::make_pair(7, 201));
  EXPECT_EQ(dark_min_max(v.data() + 1, 999), std::make_pair(100, 100));
  EXPECT_EQ(dark_min_max(v.data(), 0), std::make_pair(0, 0));
}

}  // namespace
}  // namespace faultline::corruption
