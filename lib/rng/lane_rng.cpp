// Lock-step xoshiro256++ lanes: seeding and the scalar step.
#include "rng/lane_rng.hpp"

namespace faultline::rng {

LaneRng::LaneRng(FastRng& seed_source) {
  std::uint64_t x = seed_source.next_u64();
  for (int l = 0; l < kLanes; ++l) {
    for (int k = 0; k < 4; ++k) s[k][l] = splitmix64(x);
  }
}

void LaneRng::next_values(std::uint32_t out[kValuesPerStep]) {
  auto rotl = [](std::uint64_t v, int k) { return (v << k) | (v >> (64 - k)); };
  for (int l = 0; l < kLanes; ++l) {
    std::uint64_t s0 = s[0][l], s1 = s[1][l], s2 = s[2][l], s3 = s[3][l];
    const std::uint64_t result = rotl(s0 + s3, 23) + s0;
    const std::uint64_t t = s1 << 17;
    s2 ^= s0;
    s3 ^= s1;
    s1 ^= s2;
    s0 ^= s3;
    s2 ^= t;
    s3 = rotl(s3, 45);
    s[0][l] = s0, s[1][l] = s1, s[2][l] = s2, s[3][l] = s3;
    out[2 * l] = static_cast<std::uint32_t>(result);
    out[2 * l + 1] = static_cast<std::uint32_t>(result >> 32);
  }
}

}  // namespace faultline::rng
