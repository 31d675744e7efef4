// Fast-mode Dark sampling loop: one packed alias-table lookup per element, driven by lock-step
// xoshiro lanes. An AVX2 body (vector generator + gathers) and a scalar body give the same bytes
// for the same generator state.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>

#include "rng/lane_rng.hpp"

namespace faultline::corruption {

// Alias entry packing: threshold << 8 | alias, with a 23-bit threshold. A 32-bit random value r
// picks bucket r >> 24 and keeps it when (r & 0x7FFFFF) < threshold; otherwise the outcome is the
// alias.
constexpr int kDarkAliasThresholdBits = 23;

// Walker alias table over 256 outcomes with 23-bit thresholds, packed as threshold << 8 | alias so
// one load serves a sample (one 32-bit random value per sample; each outcome's probability is
// quantised below 2^-31, far under the statistical tolerances). prob[0..256) need not sum to 1 (it
// is normalised). Writes entry[0..256).
void build_alias_entries(const double* prob, std::uint32_t* entry);

// {min, max} of n bytes ({0, 0} when n = 0).
std::pair<int, int> dark_min_max(const std::uint8_t* src, std::size_t n);

// dst[i] = sample from table row src[i] - lo, where `tables` holds 256 packed entries per input
// level lo..hi (every src[i] must lie in that range). Element i takes value i % 16 of generator
// step i / 16 (a step's leftover values after the last element are discarded). `allow_simd` = false
// forces the scalar body (tests). Not thread-safe on `rng`; src and dst must not overlap.
void dark_sample(const std::uint32_t* tables, int lo, const std::uint8_t* src, std::uint8_t* dst,
                 std::size_t n, rng::LaneRng& rng, bool allow_simd = true);

}  // namespace faultline::corruption
