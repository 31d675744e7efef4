// Brightness: skimage HSV round trip per pixel, plus a fast path reading the same results from
// tables built with it.
#include "corruption/brightness.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "common/simd.hpp"
#include "corruption/skimage_hsv.hpp"

namespace faultline::corruption {
namespace {

using skimage::to_u8;

// One pixel through rgb2hsv, V += c, hsv2rgb (skimage 0.19 semantics, channels in stored order).
void hsv_shift_pixel(const std::uint8_t* in, std::uint8_t* out, double c) {
  const skimage::Hsv hsv = skimage::rgb_to_hsv(in);
  skimage::hsv_to_rgb_u8(hsv.h, hsv.s, std::min(std::max(hsv.v + c, 0.0), 1.0), out);
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

// Slot of a pixel with three distinct channels in the ambiguity table, by key = 3 * (max position)
// + (middle position); keys 0, 4 and 8 cannot occur.
constexpr int kSlotOfKey[8] = {0, 0, 1, 2, 0, 3, 4, 5};
constexpr int kKeyOfSlot[6] = {1, 2, 3, 5, 6, 7};

// Per-severity tables, built once per process (severity is fixed per stream, so every later frame
// reuses them). Together they give the exact HSV-path output of every pixel, so neither path below
// ever runs the HSV path.
//
// Why a channel's role decides it: in every sector the maximum channel gets V2 and the minimum gets
// p = V2 * (1 - S), which depend only on (v, min); the middle channel gets q or t, a * V2 / V up to
// a few ulps. Ties need nothing more: two equal channels make h an integer k (the differences are
// exact negations of delta), k / 6 * 6 == k in double for k = 0..5, so f = 0, and q (or t) comes
// out as exactly V2 at a tie at the max and exactly p at a tie at the min; a grey pixel (S = 0)
// gets V2 in all three.
struct BrightnessTables {
  // roles[v * 256 + a], for channel value a <= v in a pixel whose max is v:
  //   bits 0-7   as the minimum: to_u8(p), exact;
  //   bits 8-15  to_u8(V2), the output of the maximum (the same in every entry of row v), exact;
  //   bits 16-31 as the middle of three distinct channels: the closed form a * V2 / V truncated,
  //   or, when that
  //              lies within 1e-6 of a truncation boundary (float noise decides), 256 + the 16-byte
  //              block of this (v, a) in `amb`.
  std::vector<std::uint32_t> roles;
  // amb[16 * block + 6 * mn + slot]: exact output of the middle channel of a pixel (v, a, mn) whose
  // middle value is ambiguous, by min value mn < a and slot (kSlotOfKey). Three bytes of slack for
  // 32-bit gathers.
  std::vector<std::uint8_t> amb;
};

BrightnessTables build_tables(double c) {
  BrightnessTables t;
  t.roles.assign(256 * 256, 0);
  for (int v = 0; v < 256; ++v) {
    const double vf = v / 255.0;
    const double v2 = std::min(std::max(vf + c, 0.0), 1.0);
    const std::uint32_t as_max = to_u8(v2);
    for (int a = 0; a <= v; ++a) {
      std::uint32_t as_min = as_max, as_mid = as_max;
      if (a < v) {
        const double s = (vf - a / 255.0) / vf;  // the HSV path's S = delta / V, with a the minimum
        as_min = to_u8(v2 * (1.0 - s));
        const double e = std::min((a / 255.0) * (v2 / vf), 1.0) * 255.0;
        const double lo = std::floor(e - 1e-6), hi = std::floor(e + 1e-6);
        if (a == 0) {
          as_mid = 0;  // never the middle of three distinct channels
        } else if (lo == hi) {
          as_mid = static_cast<std::uint32_t>(std::min(hi, 255.0));
        } else {
          t.amb.resize((t.amb.size() + 15) / 16 * 16);
          as_mid = 256 + static_cast<std::uint32_t>(t.amb.size() / 16);
          for (int mn = 0; mn < a; ++mn) {
            for (const int key : kKeyOfSlot) {
              std::uint8_t px[3], o[3];
              px[key / 3] = static_cast<std::uint8_t>(v);
              px[key % 3] = static_cast<std::uint8_t>(a);
              px[3 - key / 3 - key % 3] = static_cast<std::uint8_t>(mn);
              hsv_shift_pixel(px, o, c);
              t.amb.push_back(o[key % 3]);
            }
          }
        }
      }
      t.roles[static_cast<std::size_t>(v * 256 + a)] = as_min | (as_max << 8) | (as_mid << 16);
    }
  }
  if (t.amb.size() / 16 + 256 > 0xFFFF)
    throw std::logic_error("brightness: ambiguity table outgrew its index");
  t.amb.resize(t.amb.size() + 3);
  return t;
}

const BrightnessTables& tables_for(int severity) {
  static std::once_flag once[5];
  static BrightnessTables tables[5];
  const int i = std::clamp(severity, 1, 5) - 1;
  std::call_once(once[i], [&] { tables[i] = build_tables(brightness_offset(severity)); });
  return tables[i];
}

// Exact output of one pixel from the tables (the scalar path, also the vector path's tail).
inline void table_pixel(const BrightnessTables& t, const std::uint8_t* px, std::uint8_t* o) {
  const int v = std::max(std::max(px[0], px[1]), px[2]),
            mn = std::min(std::min(px[0], px[1]), px[2]);
  const int mid = px[0] + px[1] + px[2] - v - mn;
  const std::uint32_t at_min = t.roles[static_cast<std::size_t>(v * 256 + mn)];
  const auto as_min = static_cast<std::uint8_t>(at_min),
             as_max = static_cast<std::uint8_t>(at_min >> 8);
  std::uint32_t mid_out = t.roles[static_cast<std::size_t>(v * 256 + mid)] >> 16;
  if (mid_out > 255 && mid != mn) {
    const int pmax = v == px[0] ? 0 : (v == px[1] ? 1 : 2),
              pmid = mid == px[0] ? 0 : (mid == px[1] ? 1 : 2);
    mid_out = t.amb[16 * (mid_out - 256) +
                    static_cast<std::size_t>(6 * mn + kSlotOfKey[3 * pmax + pmid])];
  }
  for (int k = 0; k < 3; ++k) {
    o[k] = px[k] == v ? as_max : (px[k] == mn ? as_min : static_cast<std::uint8_t>(mid_out));
  }
}

#if FAULTLINE_X86_SIMD
// 8 pixels per step: deinterleave, max/min/middle per pixel, two gathers from the role table, a
// gather from the ambiguity table for ambiguous middle channels (only in steps that have one),
// select by role, re-interleave. Returns the number of pixels processed (a multiple of 8, leaving
// >= 32 bytes of slack for the 32-byte loads and 16-byte stores).
FAULTLINE_TARGET("avx2")
std::size_t brightness_avx2(const std::uint8_t* src, std::uint8_t* dst, std::size_t npx,
                            const BrightnessTables& t) {
  const auto* roles = reinterpret_cast<const int*>(t.roles.data());
  const auto* amb = reinterpret_cast<const int*>(t.amb.data());
  const __m256i to_lanes = _mm256_setr_epi32(0, 1, 2, 0, 3, 4, 5, 0);
  const __m256i pick0 =
      _mm256_setr_epi8(0, -1, -1, -1, 3, -1, -1, -1, 6, -1, -1, -1, 9, -1, -1, -1, 0, -1, -1, -1, 3,
                       -1, -1, -1, 6, -1, -1, -1, 9, -1, -1, -1);
  const __m256i pick1 =
      _mm256_setr_epi8(1, -1, -1, -1, 4, -1, -1, -1, 7, -1, -1, -1, 10, -1, -1, -1, 1, -1, -1, -1,
                       4, -1, -1, -1, 7, -1, -1, -1, 10, -1, -1, -1);
  const __m256i pick2 =
      _mm256_setr_epi8(2, -1, -1, -1, 5, -1, -1, -1, 8, -1, -1, -1, 11, -1, -1, -1, 2, -1, -1, -1,
                       5, -1, -1, -1, 8, -1, -1, -1, 11, -1, -1, -1);
  const __m256i pack = _mm256_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1, 0,
                                        1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1);
  const __m256i slot_of_key = _mm256_setr_epi32(0, 0, 1, 2, 0, 3, 4, 5);
  const __m256i byte = _mm256_set1_epi32(0xFF);
  const __m256i k255 = _mm256_set1_epi32(255);
  const __m256i k256 = _mm256_set1_epi32(256);
  // The previous step's input and output: a step repeating it (flat regions of rendered frames)
  // just stores the output again. They start as 8 black pixels, which all become grey to_u8(c)
  // (roles[0], bits 8-15).
  __m256i prev_in = _mm256_setzero_si256();
  const auto grey = static_cast<int>(((t.roles[0] >> 8) & 0xFF) * 0x010101u);
  __m256i prev_out = _mm256_shuffle_epi8(_mm256_set1_epi32(grey), pack);
  std::size_t i = 0;
  for (; (i + 8) * 3 + 8 <= npx * 3; i += 8) {
    const __m256i in = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src + 3 * i));
    __m256i packed = prev_out;
    if ((static_cast<unsigned>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(in, prev_in))) & 0xFFFFFFu) !=
        0xFFFFFFu) {
      const __m256i raw = _mm256_permutevar8x32_epi32(in, to_lanes);
      const __m256i c0 = _mm256_shuffle_epi8(raw, pick0);
      const __m256i c1 = _mm256_shuffle_epi8(raw, pick1);
      const __m256i c2 = _mm256_shuffle_epi8(raw, pick2);
      const __m256i v = _mm256_max_epi32(_mm256_max_epi32(c0, c1), c2);
      const __m256i mn = _mm256_min_epi32(_mm256_min_epi32(c0, c1), c2);
      const __m256i mid =
          _mm256_sub_epi32(_mm256_sub_epi32(_mm256_add_epi32(_mm256_add_epi32(c0, c1), c2), v), mn);
      const __m256i base = _mm256_slli_epi32(v, 8);
      const __m256i at_min = _mm256_i32gather_epi32(roles, _mm256_add_epi32(base, mn), 4);
      __m256i mid_out =
          _mm256_srli_epi32(_mm256_i32gather_epi32(roles, _mm256_add_epi32(base, mid), 4), 16);
      const __m256i as_min = _mm256_and_si256(at_min, byte);
      const __m256i as_max = _mm256_and_si256(_mm256_srli_epi32(at_min, 8), byte);
      const __m256i mx0 = _mm256_cmpeq_epi32(c0, v), mx1 = _mm256_cmpeq_epi32(c1, v),
                    mx2 = _mm256_cmpeq_epi32(c2, v);
      const __m256i mn0 = _mm256_cmpeq_epi32(c0, mn), mn1 = _mm256_cmpeq_epi32(c1, mn),
                    mn2 = _mm256_cmpeq_epi32(c2, mn);
      // Ambiguous middle channel of a pixel with distinct channels: its exact value from the
      // ambiguity table (the other lanes keep theirs, below 256 wherever it is used: a middle tied
      // with the max or min is not).
      const __m256i ambiguous =
          _mm256_andnot_si256(_mm256_cmpeq_epi32(mid, mn), _mm256_cmpgt_epi32(mid_out, k255));
      if (!_mm256_testz_si256(ambiguous, ambiguous)) {
        // key = 3 * (max position) + (middle position), positions from the -1/0 compare masks.
        const __m256i pmax = _mm256_sub_epi32(_mm256_setzero_si256(),
                                              _mm256_add_epi32(mx1, _mm256_add_epi32(mx2, mx2)));
        const __m256i md1 = _mm256_andnot_si256(_mm256_or_si256(mx1, mn1), _mm256_set1_epi32(1));
        const __m256i md2 = _mm256_andnot_si256(_mm256_or_si256(mx2, mn2), _mm256_set1_epi32(2));
        const __m256i key = _mm256_add_epi32(_mm256_add_epi32(pmax, _mm256_add_epi32(pmax, pmax)),
                                             _mm256_or_si256(md1, md2));
        const __m256i at = _mm256_add_epi32(
            _mm256_add_epi32(_mm256_slli_epi32(_mm256_sub_epi32(mid_out, k256), 4),
                             _mm256_add_epi32(_mm256_slli_epi32(mn, 2), _mm256_slli_epi32(mn, 1))),
            _mm256_permutevar8x32_epi32(slot_of_key, key));
        mid_out =
            _mm256_and_si256(_mm256_mask_i32gather_epi32(mid_out, amb, at, ambiguous, 1), byte);
      }
      // Per channel: the max role wins, then the min role, else the middle (a lambda would lose the
      // target).
      const __m256i o0 = _mm256_blendv_epi8(_mm256_blendv_epi8(mid_out, as_min, mn0), as_max, mx0);
      const __m256i o1 = _mm256_blendv_epi8(_mm256_blendv_epi8(mid_out, as_min, mn1), as_max, mx1);
      const __m256i o2 = _mm256_blendv_epi8(_mm256_blendv_epi8(mid_out, as_min, mn2), as_max, mx2);
      const __m256i out =
          _mm256_or_si256(_mm256_or_si256(o0, _mm256_slli_epi32(o1, 8)), _mm256_slli_epi32(o2, 16));
      packed = _mm256_shuffle_epi8(out, pack);
      prev_in = in;
      prev_out = packed;
    }
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + 3 * i), _mm256_castsi256_si128(packed));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + 3 * i + 12),
                     _mm256_extracti128_si256(packed, 1));
  }
  return i;
}
#endif

}  // namespace

cv::Mat brightness_fast(const cv::Mat& bgr, int severity) {
  const BrightnessTables& t = tables_for(severity);
  const cv::Mat in = continuous(bgr);
  cv::Mat out(in.size(), in.type());
  const std::size_t n = in.total();
  const std::uint8_t* src = in.data;
  std::uint8_t* dst = out.data;
  std::size_t i = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) i = brightness_avx2(src, dst, n, t);
#endif
  for (; i < n; ++i) table_pixel(t, src + 3 * i, dst + 3 * i);
  return out;
}

}  // namespace faultline::corruption
