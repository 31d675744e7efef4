// Fast generator for fast mode: xoshiro256++ seeded by splitmix64, a 128-layer ziggurat normal and
// exact Poisson samplers. Statistically equivalent to NumPy's streams, not draw-for-draw equal.
#pragma once

#include <array>
#include <cstdint>

namespace faultline::rng {

// splitmix64: advances `x` by one step and returns the next output (seeds xoshiro states).
inline std::uint64_t splitmix64(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Not thread-safe; one instance per stream. Copyable, so a stream can be forked deterministically.
class FastRng {
 public:
  explicit FastRng(std::uint64_t seed);

  std::uint64_t next_u64() {
    const std::uint64_t result = rotl(s_[0] + s_[3], 23) + s_[0];
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  std::uint32_t next_u32() { return static_cast<std::uint32_t>(next_u64() >> 32); }

  // Uniform double in [0, 1) with 53 random bits.
  double random_sample() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * random_sample(); }

  // Standard normal by the Marsaglia-Tsang ziggurat (exact up to 32-bit resolution).
  double standard_normal() {
    const auto hz = static_cast<std::int32_t>(next_u32());
    const std::uint32_t iz = static_cast<std::uint32_t>(hz) & 127u;
    if (static_cast<std::uint32_t>(hz < 0 ? -static_cast<std::int64_t>(hz) : hz) < kn_[iz]) {
      return hz * wn_[iz];
    }
    return normal_tail(hz, iz);
  }
  double normal(double loc, double scale) { return loc + scale * standard_normal(); }

  // The ziggurat's layer tables, and its slow path for a 32-bit draw hz with iz = hz & 127 that a
  // vector sampler did not accept itself (continues exactly as standard_normal() does after failing
  // |hz| < kn[iz]; draws from *this).
  const std::array<std::uint32_t, 128>& ziggurat_kn() const { return kn_; }
  const std::array<double, 128>& ziggurat_wn() const { return wn_; }
  double standard_normal_slow(std::int32_t hz) {
    return normal_tail(hz, static_cast<std::uint32_t>(hz) & 127u);
  }

  // Poisson(lam): inversion for lam < 10, PTRS otherwise; lam <= 0 gives 0.
  std::int64_t poisson(double lam);

  // Uniform integer in [0, n) for n >= 1 (Lemire's multiply-and-reject, unbiased).
  std::uint32_t bounded(std::uint32_t n) {
    std::uint64_t m = static_cast<std::uint64_t>(next_u32()) * n;
    if (static_cast<std::uint32_t>(m) < n) {
      const std::uint32_t threshold = static_cast<std::uint32_t>(-n) % n;
      while (static_cast<std::uint32_t>(m) < threshold)
        m = static_cast<std::uint64_t>(next_u32()) * n;
    }
    return static_cast<std::uint32_t>(m >> 32);
  }

  // Same as NumpyRandomState::choice6 in distribution: uniform on 0..5.
  int choice6() {
    for (;;) {
      const std::uint32_t v = next_u32() & 7u;
      if (v <= 5u) return static_cast<int>(v);
    }
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  double normal_tail(std::int32_t hz, std::uint32_t iz);

  std::array<std::uint64_t, 4> s_{};
  std::array<std::uint32_t, 128> kn_{};
  std::array<double, 128> wn_{};
  std::array<double, 128> fn_{};
};

}  // namespace faultline::rng
