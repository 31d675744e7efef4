// Deterministic per-frame seeds: the same run seed, camera and source_seq always give the same
// draw, whatever the arrival timing. splitmix64 (Steele et al.) is a bijective 64-bit mixer, so
// distinct triples rarely collide.
#pragma once

#include <cstdint>

namespace faultline::policy {

constexpr std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Effective seed of one frame of one camera. `fault_index` separates several faults of one run (0
// leaves the triple's seed unchanged). numpy mode uses the low 32 bits (np.random.seed takes a
// uint32).
constexpr std::uint64_t frame_seed(std::uint64_t run_seed, int camera, std::uint64_t source_seq,
                                   std::size_t fault_index = 0) {
  std::uint64_t h = splitmix64(run_seed);
  h = splitmix64(h ^ static_cast<std::uint64_t>(camera));
  h = splitmix64(h ^ source_seq);
  if (fault_index != 0) h = splitmix64(h ^ (0xA5A5A5A5ull + fault_index));
  return h;
}

// Seed of a per-fault stream (camera_crash set, frame_lost masks, coherent state) in fast mode.
constexpr std::uint64_t stream_seed(std::uint64_t run_seed, std::size_t fault_index,
                                    std::uint64_t salt) {
  return splitmix64(splitmix64(run_seed ^ 0x5DEECE66Dull) ^ (fault_index << 8) ^ salt);
}

}  // namespace faultline::policy
