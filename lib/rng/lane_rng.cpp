// Lock-step xoshiro256++ lanes: seeding, the scalar step, and normals (AVX2 ziggurat with a scalar
// twin).
#include "rng/lane_rng.hpp"

#include "common/simd.hpp"
#include "rng/lane_rng_avx2.hpp"

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

namespace faultline::rng {
namespace {

struct ZigguratF {
  std::int32_t kn[128];
  float wn[128];
  explicit ZigguratF(const FastRng& rng) {
    for (int i = 0; i < 128; ++i) {
      kn[i] = static_cast<std::int32_t>(
          rng.ziggurat_kn()[static_cast<std::size_t>(i)]);  // all below 2^31
      wn[i] = static_cast<float>(rng.ziggurat_wn()[static_cast<std::size_t>(i)]);
    }
  }
};

inline float normal_value(std::uint32_t bits, const ZigguratF& z, float locf, float scalef,
                          double loc, double scale, FastRng& slow) {
  const auto hz = static_cast<std::int32_t>(bits);
  const std::uint32_t iz = bits & 127u;
  const auto mag =
      static_cast<std::int32_t>(hz < 0 ? 0u - bits : bits);  // wraps at INT32_MIN, like vpabsd
  if (z.kn[iz] > mag) return locf + scalef * (static_cast<float>(hz) * z.wn[iz]);
  return static_cast<float>(loc + scale * slow.standard_normal_slow(hz));
}

void fill_normals_scalar(float* dst, std::size_t n, double loc, double scale, const ZigguratF& z,
                         LaneRng& lanes, FastRng& slow) {
  const auto locf = static_cast<float>(loc), scalef = static_cast<float>(scale);
  std::uint32_t r[LaneRng::kValuesPerStep];
  constexpr std::size_t kStep = LaneRng::kValuesPerStep;
  for (std::size_t i = 0; i < n; i += kStep) {
    lanes.next_values(r);
    const std::size_t m = n - i < kStep ? n - i : kStep;
    for (std::size_t j = 0; j < m; ++j)
      dst[i + j] = normal_value(r[j], z, locf, scalef, loc, scale, slow);
  }
}

#if FAULTLINE_X86_SIMD

// Eight normals from eight draws; rejected lanes (rare) are redone in element order by the scalar
// definition.
FAULTLINE_TARGET("avx2")
inline void normals8(__m256i hz, const ZigguratF& z, __m256 locv, __m256 scalev, float* dst,
                     double loc, double scale, FastRng& slow) {
  const __m256i iz = _mm256_and_si256(hz, _mm256_set1_epi32(127));
  const __m256i kn = _mm256_i32gather_epi32(z.kn, iz, 4);
  const __m256 wn = _mm256_i32gather_ps(z.wn, iz, 4);
  const __m256i accept = _mm256_cmpgt_epi32(kn, _mm256_abs_epi32(hz));
  const __m256 x = _mm256_mul_ps(_mm256_cvtepi32_ps(hz), wn);
  _mm256_storeu_ps(dst, _mm256_add_ps(locv, _mm256_mul_ps(scalev, x)));
  auto rejected = static_cast<unsigned>(~_mm256_movemask_ps(_mm256_castsi256_ps(accept))) & 0xFFu;
  if (rejected != 0) {
    alignas(32) std::int32_t h[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(h), hz);
    while (rejected != 0) {
      const int j = __builtin_ctz(rejected);
      rejected &= rejected - 1;
      dst[j] = static_cast<float>(loc + scale * slow.standard_normal_slow(h[j]));
    }
  }
}

// Whole blocks of 16 (one step of both halves); returns how many it wrote.
FAULTLINE_TARGET("avx2")
std::size_t fill_normals_avx2(float* dst, std::size_t n, double loc, double scale,
                              const ZigguratF& z, LaneRng& lanes, FastRng& slow) {
  avx2::Xoshiro4 a = avx2::load_half(lanes, 0), b = avx2::load_half(lanes, 1);
  const __m256 locv = _mm256_set1_ps(static_cast<float>(loc)),
               scalev = _mm256_set1_ps(static_cast<float>(scale));
  std::size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    normals8(avx2::step(a), z, locv, scalev, dst + i, loc, scale, slow);
    normals8(avx2::step(b), z, locv, scalev, dst + i + 8, loc, scale, slow);
  }
  avx2::store_half(a, lanes, 0);
  avx2::store_half(b, lanes, 1);
  return i;
}
#endif

}  // namespace

void fill_normals(float* dst, std::size_t n, double loc, double scale, LaneRng& lanes,
                  FastRng& slow, bool allow_simd) {
  const ZigguratF z(slow);
  std::size_t done = 0;
#if FAULTLINE_X86_SIMD
  const bool has_avx2 = common::cpu_has_avx2();
  if (allow_simd && has_avx2) done = fill_normals_avx2(dst, n, loc, scale, z, lanes, slow);
#else
  (void)allow_simd;
#endif
  fill_normals_scalar(dst + done, n - done, loc, scale, z, lanes, slow);
}

}  // namespace faultline::rng
