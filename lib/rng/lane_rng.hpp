// Eight xoshiro256++ streams stepped in lock-step (fast mode): the layout an AVX2 kernel steps as
// two vectors of four 64-bit lanes, and a scalar definition of the same output so every CPU gives
// the same values for a seed.
#pragma once

#include <cstddef>
#include <cstdint>

#include "rng/fast_rng.hpp"

namespace faultline::rng {

// Not thread-safe; one instance per stream. A step advances all eight lanes once and yields 16
// 32-bit values: value 2l is the low half and value 2l + 1 the high half of lane l's output (the
// order in which two 256-bit vectors holding lanes 0-3 and 4-7 read as sixteen 32-bit integers).
struct LaneRng {
  static constexpr int kLanes = 8;
  static constexpr int kValuesPerStep = 2 * kLanes;

  // Seeds every lane from one draw of `seed_source` (advanced by one step) through splitmix64.
  explicit LaneRng(FastRng& seed_source);

  // The next 16 values (scalar reference of the vector step).
  void next_values(std::uint32_t out[kValuesPerStep]);

  alignas(32) std::uint64_t s[4][kLanes];  // s[k][l]: word k of lane l's xoshiro256++ state
};

// dst[i] = N(loc, scale) as float for i < n: element i takes value i % 16 of lane step i / 16 as
// the 32-bit draw hz of `slow`'s ziggurat (layer hz & 127, accepted when kn > |hz| in wrapping
// int32, value loc + scale * (hz * wn) in float32); draws the ziggurat rejects (about 1 %) go
// through slow.standard_normal_slow(hz) in element order. The AVX2 body and the scalar body give
// the same floats. `allow_simd` = false forces the scalar body (tests).
void fill_normals(float* dst, std::size_t n, double loc, double scale, LaneRng& lanes,
                  FastRng& slow, bool allow_simd = true);

}  // namespace faultline::rng
