// Brightness: skimage HSV round trip per pixel, plus a table-driven fast path that falls back to it near ties.
#include "corruption/brightness.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <vector>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

namespace faultline::corruption {
namespace {

std::uint8_t to_u8(double v) { return static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0); }

// One pixel through rgb2hsv, V += c, hsv2rgb (skimage 0.19 semantics, channels in stored order).
void hsv_shift_pixel(const std::uint8_t* in, std::uint8_t* out, double c) {
  const double a0 = in[0] / 255.0, a1 = in[1] / 255.0, a2 = in[2] / 255.0;
  const double v = std::max(std::max(a0, a1), a2);
  const double delta = v - std::min(std::min(a0, a1), a2);
  double s = delta / v;
  if (delta == 0.0) s = 0.0;
  double h = 0.0;
  if (a0 == v) h = (a1 - a2) / delta;
  if (a1 == v) h = 2.0 + (a2 - a0) / delta;
  if (a2 == v) h = 4.0 + (a0 - a1) / delta;
  // numpy floor-mod: fmod, then shift negatives into [0, 1). h lies in [-1, 5] (or is NaN), so |h / 6| < 1 and
  // fmod(h / 6, 1) is exactly h / 6: the libm call is skipped without changing a bit.
  double hue = h / 6.0;
  if (hue != 0.0 && hue < 0.0) hue += 1.0;
  if (delta == 0.0) hue = 0.0;
  if (std::isnan(hue)) hue = 0.0;
  if (std::isnan(s)) s = 0.0;
  const double v2 = std::min(std::max(v + c, 0.0), 1.0);
  const double hi = std::floor(hue * 6.0);
  const double f = hue * 6.0 - hi;
  const double p = v2 * (1.0 - s);
  const double q = v2 * (1.0 - f * s);
  const double t = v2 * (1.0 - (1.0 - f) * s);
  double r0 = 0.0, r1 = 0.0, r2 = 0.0;
  switch (static_cast<std::uint8_t>(hi) % 6) {
    case 0: r0 = v2, r1 = t, r2 = p; break;
    case 1: r0 = q, r1 = v2, r2 = p; break;
    case 2: r0 = p, r1 = v2, r2 = t; break;
    case 3: r0 = p, r1 = q, r2 = v2; break;
    case 4: r0 = t, r1 = p, r2 = v2; break;
    default: r0 = v2, r1 = p, r2 = q; break;
  }
  out[0] = to_u8(r0);
  out[1] = to_u8(r1);
  out[2] = to_u8(r2);
}

cv::Mat continuous(const cv::Mat& m) { return m.isContinuous() ? m : m.clone(); }

}  // namespace

double brightness_offset(int severity) {
  static constexpr double kC[] = {0.1, 0.2, 0.3, 0.4, 0.5};
  return kC[std::clamp(severity, 1, 5) - 1];
}

cv::Mat brightness_exact(const cv::Mat& bgr, int severity) {
  const double c = brightness_offset(severity);
  const cv::Mat in = continuous(bgr);
  cv::Mat out(in.size(), in.type());
  const std::size_t n = in.total();
  const std::uint8_t* src = in.data;
  std::uint8_t* dst = out.data;
  for (std::size_t i = 0; i < n; ++i) hsv_shift_pixel(src + 3 * i, dst + 3 * i, c);
  return out;
}

namespace {

// Per-severity tables, built once per process (severity is fixed per stream, so every later frame reuses them).
struct BrightnessTables {
  // main[v * 256 + a]: output for a channel a of a pixel whose max is v, or -1 when the closed form is within
  // 1e-6 of a truncation boundary (then the pixel takes the exact path). Without ties the max channel gets V2
  // exactly and a zero channel gets p = V2 * (1 - 1) = 0 exactly; the others are a * V2 / V up to a few ulps.
  std::vector<std::int16_t> main;
  // tie[pattern * 65536 + tied * 256 + other]: the exact HSV-path output (packed b | g << 8 | r << 16) of a pixel
  // with exactly two equal channels. Such a pixel is a function of those two numbers, so tabulating the exact
  // path keeps it bit-exact. Patterns: 0 = ch0 == ch1, 1 = ch1 == ch2, 2 = ch0 == ch2.
  std::vector<std::uint32_t> tie;
  std::uint8_t grey_out = 0;
  // roles[v * 256 + a] for the vector path, by the role of channel value a in a pixel whose max is v: bits 0-15
  // the exact output as the minimum channel (p = V2 * (1 - S) depends only on v and the minimum), bits 16-31 the
  // closed-form output as the middle channel or 0xFFFF when that is within 1e-6 of a truncation boundary; at
  // a == v both halves hold the output of the maximum channel, to_u8(V2) (exact for a pixel without a two-way tie).
  std::vector<std::int32_t> roles;
};

BrightnessTables build_tables(double c) {
  BrightnessTables t;
  t.main.assign(256 * 256, -1);
  for (int v = 1; v < 256; ++v) {
    const double vf = v / 255.0;
    const double v2 = std::min(std::max(vf + c, 0.0), 1.0);
    for (int a = 0; a <= v; ++a) {
      std::int16_t out = -1;
      if (a == v) {
        out = to_u8(v2);
      } else if (a == 0) {
        out = 0;
      } else {
        const double e = std::min((a / 255.0) * (v2 / vf), 1.0) * 255.0;
        const double lo = std::floor(e - 1e-6), hi = std::floor(e + 1e-6);
        if (lo == hi) out = static_cast<std::int16_t>(std::min(hi, 255.0));
      }
      t.main[static_cast<std::size_t>(v * 256 + a)] = out;
    }
  }
  t.tie.resize(3 * 65536);
  for (int pattern = 0; pattern < 3; ++pattern) {
    for (int tied = 0; tied < 256; ++tied) {
      for (int other = 0; other < 256; ++other) {
        std::uint8_t px[3];
        const auto a = static_cast<std::uint8_t>(tied), b = static_cast<std::uint8_t>(other);
        if (pattern == 0) px[0] = a, px[1] = a, px[2] = b;
        if (pattern == 1) px[0] = b, px[1] = a, px[2] = a;
        if (pattern == 2) px[0] = a, px[1] = b, px[2] = a;
        std::uint8_t o[3];
        hsv_shift_pixel(px, o, c);
        t.tie[static_cast<std::size_t>(pattern * 65536 + tied * 256 + other)] =
            o[0] | (static_cast<std::uint32_t>(o[1]) << 8) | (static_cast<std::uint32_t>(o[2]) << 16);
      }
    }
  }
  t.grey_out = to_u8(std::min(std::max(c, 0.0), 1.0));
  t.roles.assign(256 * 256, 0);
  for (int v = 0; v < 256; ++v) {
    const double vf = v / 255.0;
    const double v2 = std::min(std::max(vf + c, 0.0), 1.0);
    for (int a = 0; a <= v; ++a) {
      std::uint32_t as_min = 0, as_mid = 0xFFFF;
      if (a == v) {
        as_min = as_mid = to_u8(v2);
      } else {
        double s = (vf - a / 255.0) / vf;  // the HSV path's S = delta / V, with a the minimum
        as_min = to_u8(v2 * (1.0 - s));
        const std::int16_t closed = t.main[static_cast<std::size_t>(v * 256 + a)];
        if (closed >= 0) as_mid = static_cast<std::uint32_t>(closed);
      }
      t.roles[static_cast<std::size_t>(v * 256 + a)] = static_cast<std::int32_t>(as_min | (as_mid << 16));
    }
  }
  return t;
}

const BrightnessTables& tables_for(int severity) {
  static std::once_flag once[5];
  static BrightnessTables tables[5];
  const int i = std::clamp(severity, 1, 5) - 1;
  std::call_once(once[i], [&] { tables[i] = build_tables(brightness_offset(severity)); });
  return tables[i];
}

}  // namespace

namespace {

// Exact output of one pixel from the tables (scalar path; also resolves the pixels the vector path flags).
inline void table_pixel(const BrightnessTables& t, double c, const std::uint8_t* px, std::uint8_t* o) {
  const int b = px[0], g = px[1], r = px[2];
  const bool e01 = b == g, e12 = g == r, e02 = b == r;
  if (e01 + e12 + e02 == 1) {
    // Two equal channels put the hue on a sector boundary, where the HSV path may hand the max channel a value
    // a few ulps below V2: take the tabulated exact result.
    const int pattern = e01 ? 0 : (e12 ? 1 : 2);
    const int tied = e02 ? b : g;
    const int other = e01 ? r : (e12 ? b : g);
    const std::uint32_t packed = t.tie[static_cast<std::size_t>(pattern * 65536 + tied * 256 + other)];
    o[0] = static_cast<std::uint8_t>(packed);
    o[1] = static_cast<std::uint8_t>(packed >> 8);
    o[2] = static_cast<std::uint8_t>(packed >> 16);
    return;
  }
  const int v = std::max(std::max(b, g), r);
  if (v == 0) {
    o[0] = o[1] = o[2] = t.grey_out;
    return;
  }
  const std::int16_t* row = t.main.data() + v * 256;
  const std::int16_t r0 = row[b], r1 = row[g], r2 = row[r];
  if ((r0 | r1 | r2) < 0) {
    hsv_shift_pixel(px, o, c);
  } else {
    o[0] = static_cast<std::uint8_t>(r0);
    o[1] = static_cast<std::uint8_t>(r1);
    o[2] = static_cast<std::uint8_t>(r2);
  }
}

#if defined(__GNUC__) && defined(__x86_64__)
// 8 pixels per step: deinterleave, max/min/middle per pixel, three gathers from the role table, select by role,
// re-interleave. Pixels the role table cannot decide (see below) are listed in `flagged` for the scalar path. Returns the number of pixels processed (a multiple of 8, leaving >= 32 bytes of slack for the 32-byte
// loads and 16-byte stores).
__attribute__((target("avx2"))) std::size_t brightness_avx2(const std::uint8_t* src, std::uint8_t* dst,
                                                            std::size_t npx, const std::int32_t* roles,
                                                            std::vector<std::uint32_t>& flagged) {
  const __m256i to_lanes = _mm256_setr_epi32(0, 1, 2, 0, 3, 4, 5, 0);
  const __m256i pick0 = _mm256_setr_epi8(0, -1, -1, -1, 3, -1, -1, -1, 6, -1, -1, -1, 9, -1, -1, -1, 0, -1, -1, -1,
                                         3, -1, -1, -1, 6, -1, -1, -1, 9, -1, -1, -1);
  const __m256i pick1 = _mm256_setr_epi8(1, -1, -1, -1, 4, -1, -1, -1, 7, -1, -1, -1, 10, -1, -1, -1, 1, -1, -1,
                                         -1, 4, -1, -1, -1, 7, -1, -1, -1, 10, -1, -1, -1);
  const __m256i pick2 = _mm256_setr_epi8(2, -1, -1, -1, 5, -1, -1, -1, 8, -1, -1, -1, 11, -1, -1, -1, 2, -1, -1,
                                         -1, 5, -1, -1, -1, 8, -1, -1, -1, 11, -1, -1, -1);
  const __m256i pack = _mm256_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1, 0, 1, 2, 4, 5, 6, 8,
                                        9, 10, 12, 13, 14, -1, -1, -1, -1);
  const __m256i lo16 = _mm256_set1_epi32(0xFFFF);
  const __m256i one = _mm256_set1_epi32(1);
  std::size_t i = 0;
  for (; (i + 8) * 3 + 8 <= npx * 3; i += 8) {
    const __m256i raw = _mm256_permutevar8x32_epi32(
        _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src + 3 * i)), to_lanes);
    const __m256i c0 = _mm256_shuffle_epi8(raw, pick0);
    const __m256i c1 = _mm256_shuffle_epi8(raw, pick1);
    const __m256i c2 = _mm256_shuffle_epi8(raw, pick2);
    const __m256i v = _mm256_max_epi32(_mm256_max_epi32(c0, c1), c2);
    const __m256i mn = _mm256_min_epi32(_mm256_min_epi32(c0, c1), c2);
    const __m256i mid = _mm256_sub_epi32(_mm256_sub_epi32(_mm256_add_epi32(_mm256_add_epi32(c0, c1), c2), v), mn);
    const __m256i base = _mm256_slli_epi32(v, 8);
    const __m256i as_min = _mm256_and_si256(_mm256_i32gather_epi32(roles, _mm256_add_epi32(base, mn), 4), lo16);
    const __m256i as_mid = _mm256_srli_epi32(_mm256_i32gather_epi32(roles, _mm256_add_epi32(base, mid), 4), 16);
    const __m256i as_max = _mm256_and_si256(_mm256_i32gather_epi32(roles, _mm256_add_epi32(base, v), 4), lo16);
    // Per channel: the max role wins, then the min role, else the middle (a lambda would lose the target).
    const __m256i o0 = _mm256_blendv_epi8(_mm256_blendv_epi8(as_mid, as_min, _mm256_cmpeq_epi32(c0, mn)), as_max,
                                          _mm256_cmpeq_epi32(c0, v));
    const __m256i o1 = _mm256_blendv_epi8(_mm256_blendv_epi8(as_mid, as_min, _mm256_cmpeq_epi32(c1, mn)), as_max,
                                          _mm256_cmpeq_epi32(c1, v));
    const __m256i o2 = _mm256_blendv_epi8(_mm256_blendv_epi8(as_mid, as_min, _mm256_cmpeq_epi32(c2, mn)), as_max,
                                          _mm256_cmpeq_epi32(c2, v));
    // Flagged: two channels tied at the max (one of them may get V2 minus a few ulps), or a middle value within
    // 1e-6 of a truncation boundary. A pixel with its two smaller channels tied is safe unless that value is
    // ambiguous (then mid == mn is flagged here too): both get p up to a few ulps, which truncate alike.
    const __m256i at_max = _mm256_add_epi32(
        _mm256_add_epi32(_mm256_and_si256(_mm256_cmpeq_epi32(c0, v), one),
                         _mm256_and_si256(_mm256_cmpeq_epi32(c1, v), one)),
        _mm256_and_si256(_mm256_cmpeq_epi32(c2, v), one));
    const __m256i flag = _mm256_or_si256(_mm256_cmpeq_epi32(at_max, _mm256_set1_epi32(2)),
                                         _mm256_cmpeq_epi32(as_mid, lo16));
    const __m256i packed = _mm256_shuffle_epi8(
        _mm256_or_si256(_mm256_or_si256(o0, _mm256_slli_epi32(o1, 8)), _mm256_slli_epi32(o2, 16)), pack);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + 3 * i), _mm256_castsi256_si128(packed));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + 3 * i + 12), _mm256_extracti128_si256(packed, 1));
    unsigned m = static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(flag)));
    while (m != 0) {
      flagged.push_back(static_cast<std::uint32_t>(i) + static_cast<std::uint32_t>(__builtin_ctz(m)));
      m &= m - 1;
    }
  }
  return i;
}

bool have_avx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}
#endif

}  // namespace

cv::Mat brightness_fast(const cv::Mat& bgr, int severity) {
  const double c = brightness_offset(severity);
  const BrightnessTables& t = tables_for(severity);
  const cv::Mat in = continuous(bgr);
  cv::Mat out(in.size(), in.type());
  const std::size_t n = in.total();
  const std::uint8_t* src = in.data;
  std::uint8_t* dst = out.data;
  std::size_t i = 0;
#if defined(__GNUC__) && defined(__x86_64__)
  if (have_avx2() && n < (std::size_t{1} << 31)) {
    thread_local std::vector<std::uint32_t> flagged;
    flagged.clear();
    i = brightness_avx2(src, dst, n, t.roles.data(), flagged);
    for (const std::uint32_t k : flagged) table_pixel(t, c, src + 3 * std::size_t{k}, dst + 3 * std::size_t{k});
  }
#endif
  for (; i < n; ++i) table_pixel(t, c, src + 3 * i, dst + 3 * i);
  return out;
}

}  // namespace faultline::corruption
