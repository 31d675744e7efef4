// Fog plasma row kernels: the diamond-square passes, min/max, normalisation and the fast mode's
// uniform draws. AVX2 intrinsics bodies (no FMA: every product is rounded before its sum, like
// NumPy) and the scalar bodies they must equal bit for bit. The library is compiled with
// -ffp-contract=off.
#include <algorithm>
#include <array>
#include <cstring>

#include "common/simd.hpp"
#include "corruption/fog_kernels.hpp"
#include "rng/lane_rng_avx2.hpp"

namespace faultline::corruption {
namespace {

inline double offset(const FogStep& s, double u) { return s.w * (s.lo + s.span * u); }

void centre_scalar(const double* c0, const double* c1, const double* u, double* d, int j, int count,
                   const FogStep& s) {
  for (; j < count; ++j) d[j] = ((c0[j] + c1[j]) + (c0[j + 1] + c1[j + 1])) / 4 + offset(s, u[j]);
}
void hedge_scalar(const double* d0, const double* dp, const double* c0, const double* u, double* e,
                  int j, int count, const FogStep& s) {
  for (; j < count; ++j) e[j] = ((d0[j] + dp[j]) + (c0[j] + c0[j + 1])) / 4 + offset(s, u[j]);
}
void vedge_scalar(const double* d0, const double* c0, const double* c1, const double* u, double* e,
                  int j, int count, const FogStep& s) {
  for (; j < count; ++j) e[j] = ((d0[j] + d0[j - 1]) + (c0[j] + c1[j])) / 4 + offset(s, u[j]);
}

// A uniform on [0, 1) from 64 random bits: the top 52 as the mantissa of a double in [1, 2), minus
// 1 (exact).
inline double uniform52(std::uint64_t bits) {
  const std::uint64_t v = (bits >> 12) | 0x3FF0000000000000ULL;
  double d;
  std::memcpy(&d, &v, sizeof d);
  return d - 1.0;
}
void fill_uniforms_scalar(rng::LaneRng& lanes, double* u, int i, int count) {
  std::uint32_t r[rng::LaneRng::kValuesPerStep];
  for (; i < count; i += rng::LaneRng::kLanes) {
    lanes.next_values(r);
    for (int l = 0; l < rng::LaneRng::kLanes && i + l < count; ++l) {
      u[i + l] = uniform52(static_cast<std::uint64_t>(r[2 * l]) |
                           static_cast<std::uint64_t>(r[2 * l + 1]) << 32);
    }
  }
}

#if FAULTLINE_X86_SIMD

struct StepVec {
  __m256d w, lo, span;
};
FAULTLINE_TARGET_INLINE("avx2") inline StepVec step_vec(const FogStep& s) {
  return {_mm256_set1_pd(s.w), _mm256_set1_pd(s.lo), _mm256_set1_pd(s.span)};
}
// sum / 4 + w * (lo + span * u): x / 4 and x * 0.25 are the same correctly rounded value.
FAULTLINE_TARGET_INLINE("avx2")
inline __m256d point(__m256d sum, const double* u, const StepVec& v) {
  const __m256d off =
      _mm256_mul_pd(v.w, _mm256_add_pd(v.lo, _mm256_mul_pd(v.span, _mm256_loadu_pd(u))));
  return _mm256_add_pd(_mm256_mul_pd(sum, _mm256_set1_pd(0.25)), off);
}

FAULTLINE_TARGET("avx2")
void centre_avx2(const double* c0, const double* c1, const double* u, double* d, int count,
                 const FogStep& s) {
  const StepVec v = step_vec(s);
  int j = 0;
  for (; j + 4 <= count; j += 4) {
    const __m256d a = _mm256_add_pd(_mm256_loadu_pd(c0 + j), _mm256_loadu_pd(c1 + j));
    const __m256d b = _mm256_add_pd(_mm256_loadu_pd(c0 + j + 1), _mm256_loadu_pd(c1 + j + 1));
    _mm256_storeu_pd(d + j, point(_mm256_add_pd(a, b), u + j, v));
  }
  centre_scalar(c0, c1, u, d, j, count, s);
}

FAULTLINE_TARGET("avx2")
void hedge_avx2(const double* d0, const double* dp, const double* c0, const double* u, double* e,
                int count, const FogStep& s) {
  const StepVec v = step_vec(s);
  int j = 0;
  for (; j + 4 <= count; j += 4) {
    const __m256d a = _mm256_add_pd(_mm256_loadu_pd(d0 + j), _mm256_loadu_pd(dp + j));
    const __m256d b = _mm256_add_pd(_mm256_loadu_pd(c0 + j), _mm256_loadu_pd(c0 + j + 1));
    _mm256_storeu_pd(e + j, point(_mm256_add_pd(a, b), u + j, v));
  }
  hedge_scalar(d0, dp, c0, u, e, j, count, s);
}

FAULTLINE_TARGET("avx2")
void vedge_avx2(const double* d0, const double* c0, const double* c1, const double* u, double* e,
                int count, const FogStep& s) {
  const StepVec v = step_vec(s);
  int j = 0;
  for (; j + 4 <= count; j += 4) {
    const __m256d a = _mm256_add_pd(_mm256_loadu_pd(d0 + j), _mm256_loadu_pd(d0 + j - 1));
    const __m256d b = _mm256_add_pd(_mm256_loadu_pd(c0 + j), _mm256_loadu_pd(c1 + j));
    _mm256_storeu_pd(e + j, point(_mm256_add_pd(a, b), u + j, v));
  }
  vedge_scalar(d0, c0, c1, u, e, j, count, s);
}

FAULTLINE_TARGET("avx2")
void interleave_avx2(const double* a, const double* b, double* out, int pairs) {
  int j = 0;
  for (; j + 4 <= pairs; j += 4) {
    const __m256d va = _mm256_loadu_pd(a + j), vb = _mm256_loadu_pd(b + j);
    const __m256d lo = _mm256_unpacklo_pd(va, vb),
                  hi = _mm256_unpackhi_pd(va, vb);  // a0 b0 a2 b2 | a1 b1 a3 b3
    _mm256_storeu_pd(out + 2 * j, _mm256_permute2f128_pd(lo, hi, 0x20));
    _mm256_storeu_pd(out + 2 * j + 4, _mm256_permute2f128_pd(lo, hi, 0x31));
  }
  for (; j < pairs; ++j) {
    out[2 * j] = a[j];
    out[2 * j + 1] = b[j];
  }
}

FAULTLINE_TARGET("avx2") void minmax_avx2(const double* p, int count, double* mn, double* mx) {
  int j = 0;
  double lo = *mn, hi = *mx;
  if (count >= 8) {
    __m256d vlo0 = _mm256_set1_pd(lo), vhi0 = _mm256_set1_pd(hi), vlo1 = vlo0, vhi1 = vhi0;
    for (; j + 8 <= count; j += 8) {
      const __m256d a = _mm256_loadu_pd(p + j), b = _mm256_loadu_pd(p + j + 4);
      vlo0 = _mm256_min_pd(vlo0, a);
      vhi0 = _mm256_max_pd(vhi0, a);
      vlo1 = _mm256_min_pd(vlo1, b);
      vhi1 = _mm256_max_pd(vhi1, b);
    }
    alignas(32) double l[4], h[4];
    _mm256_store_pd(l, _mm256_min_pd(vlo0, vlo1));
    _mm256_store_pd(h, _mm256_max_pd(vhi0, vhi1));
    lo = std::min({l[0], l[1], l[2], l[3]});
    hi = std::max({h[0], h[1], h[2], h[3]});
  }
  for (; j < count; ++j) {
    lo = std::min(lo, p[j]);
    hi = std::max(hi, p[j]);
  }
  *mn = lo;
  *mx = hi;
}

FAULTLINE_TARGET("avx2")
void interleave_normalise_avx2(const double* a, const double* b, double* out, int pairs, double mn,
                               double range) {
  const __m256d vmn = _mm256_set1_pd(mn), vr = _mm256_set1_pd(range);
  int j = 0;
  for (; j + 4 <= pairs; j += 4) {
    const __m256d va = _mm256_div_pd(_mm256_sub_pd(_mm256_loadu_pd(a + j), vmn), vr);
    const __m256d vb = _mm256_div_pd(_mm256_sub_pd(_mm256_loadu_pd(b + j), vmn), vr);
    const __m256d lo = _mm256_unpacklo_pd(va, vb), hi = _mm256_unpackhi_pd(va, vb);
    _mm256_storeu_pd(out + 2 * j, _mm256_permute2f128_pd(lo, hi, 0x20));
    _mm256_storeu_pd(out + 2 * j + 4, _mm256_permute2f128_pd(lo, hi, 0x31));
  }
  for (; j < pairs; ++j) {
    out[2 * j] = (a[j] - mn) / range;
    out[2 * j + 1] = (b[j] - mn) / range;
  }
}

FAULTLINE_TARGET_INLINE("avx2") inline __m256d uniform52_avx2(__m256i bits) {
  const __m256i v =
      _mm256_or_si256(_mm256_srli_epi64(bits, 12), _mm256_set1_epi64x(0x3FF0000000000000LL));
  return _mm256_sub_pd(_mm256_castsi256_pd(v), _mm256_set1_pd(1.0));
}
// Both halves of the lanes stepped together (two independent chains); a partial last step goes
// through the scalar definition (same values).
FAULTLINE_TARGET("avx2") void fill_uniforms_avx2(rng::LaneRng& lanes, double* u, int count) {
  rng::avx2::Xoshiro4 a = rng::avx2::load_half(lanes, 0), b = rng::avx2::load_half(lanes, 1);
  int i = 0;
  for (; i + rng::LaneRng::kLanes <= count; i += rng::LaneRng::kLanes) {
    _mm256_storeu_pd(u + i, uniform52_avx2(rng::avx2::step(a)));
    _mm256_storeu_pd(u + i + 4, uniform52_avx2(rng::avx2::step(b)));
  }
  rng::avx2::store_half(a, lanes, 0);
  rng::avx2::store_half(b, lanes, 1);
  fill_uniforms_scalar(lanes, u, i, count);
}

#endif

}  // namespace

void fog_centre_row(const double* c0, const double* c1, const double* u, double* d, int count,
                    const FogStep& s) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return centre_avx2(c0, c1, u, d, count, s);
#endif
  centre_scalar(c0, c1, u, d, 0, count, s);
}

void fog_hedge_row(const double* d0, const double* dp, const double* c0, const double* u, double* e,
                   int count, const FogStep& s) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return hedge_avx2(d0, dp, c0, u, e, count, s);
#endif
  hedge_scalar(d0, dp, c0, u, e, 0, count, s);
}

void fog_vedge_row(const double* d0, const double* c0, const double* c1, const double* u, double* e,
                   int count, const FogStep& s) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return vedge_avx2(d0, c0, c1, u, e, count, s);
#endif
  vedge_scalar(d0, c0, c1, u, e, 0, count, s);
}

void fog_interleave_row(const double* a, const double* b, double* out, int pairs) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return interleave_avx2(a, b, out, pairs);
#endif
  for (int j = 0; j < pairs; ++j) {
    out[2 * j] = a[j];
    out[2 * j + 1] = b[j];
  }
}

void fog_minmax_row(const double* p, int count, double* mn, double* mx) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return minmax_avx2(p, count, mn, mx);
#endif
  for (int j = 0; j < count; ++j) {
    *mn = std::min(*mn, p[j]);
    *mx = std::max(*mx, p[j]);
  }
}

void fog_interleave_normalise_row(const double* a, const double* b, double* out, int pairs,
                                  double mn, double range) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return interleave_normalise_avx2(a, b, out, pairs, mn, range);
#endif
  for (int j = 0; j < pairs; ++j) {
    out[2 * j] = (a[j] - mn) / range;
    out[2 * j + 1] = (b[j] - mn) / range;
  }
}

void fog_fill_uniforms(rng::LaneRng& lanes, double* u, int count) {
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) return fill_uniforms_avx2(lanes, u, count);
#endif
  fill_uniforms_scalar(lanes, u, 0, count);
}

}  // namespace faultline::corruption
