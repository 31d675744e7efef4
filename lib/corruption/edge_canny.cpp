// Canny (3 x 3 Sobel, L1 gradient) as OpenCV computes it: replicate border for the Sobel, zero
// magnitude outside the image for the suppression, 8-connected hysteresis.
#include "corruption/edge_canny.hpp"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "common/simd.hpp"

namespace faultline::corruption {

namespace {

// One row's Sobel derivatives and L1 magnitude from the rows above (a), at (b) and below (c),
// each padded by one replicated value each side (index 0 is column -1).
FAULTLINE_CLONES("avx2")
void gradient_row(std::int16_t* __restrict dx, std::int16_t* __restrict dy,
                  std::int16_t* __restrict mag, const std::int16_t* a, const std::int16_t* b,
                  const std::int16_t* c, std::size_t n) {
  for (std::size_t x = 0; x < n; ++x) {
    const int gx = (a[x + 2] - a[x]) + 2 * (b[x + 2] - b[x]) + (c[x + 2] - c[x]);
    const int gy = (c[x] + 2 * c[x + 1] + c[x + 2]) - (a[x] + 2 * a[x + 1] + a[x + 2]);
    dx[x] = static_cast<std::int16_t>(gx);
    dy[x] = static_cast<std::int16_t>(gy);
    mag[x] = static_cast<std::int16_t>(std::abs(gx) + std::abs(gy));
  }
}

// Non-maximum suppression and the two thresholds for one row: 1 = no edge, 0 = weak candidate,
// 2 = strong. up, mid, down: magnitudes of the rows above, at and below (index 0 is column -1,
// zero outside the image). The direction sectors at 22.5 and 67.5 degrees compare |dy| << 15
// with |dx| tan(22.5) in 15-bit fixed point, as OpenCV does; ties go as in OpenCV (>= towards
// the right or below on the axes, strict on the diagonals).
constexpr int kShift = 15;
constexpr int kTan22 = 13573;  // round(tan(22.5 degrees) 2^15)

std::uint8_t suppress_value(const std::int16_t* dx, const std::int16_t* dy, const std::int16_t* up,
                            const std::int16_t* mid, const std::int16_t* down, int low, int high,
                            std::size_t x) {
  const int m = mid[x + 1];
  if (m <= low) return 1;
  const int ax = std::abs(dx[x]);
  const int ay = std::abs(dy[x]) << kShift;
  const int tg22 = ax * kTan22;
  const int tg67 = tg22 + (ax << (kShift + 1));
  bool peak;
  if (ay < tg22) {
    peak = m > mid[x] && m >= mid[x + 2];
  } else if (ay > tg67) {
    peak = m > up[x + 1] && m >= down[x + 1];
  } else if ((dx[x] ^ dy[x]) >= 0) {
    peak = m > up[x] && m > down[x + 2];
  } else {
    peak = m > up[x + 2] && m > down[x];
  }
  return static_cast<std::uint8_t>(peak ? (m > high ? 2 : 0) : 1);
}

#if FAULTLINE_X86_SIMD
// a < b in the 16 int32 lanes of (lo, hi), as 16 int16 masks in order.
FAULTLINE_TARGET_INLINE("avx2") inline __m256i packed_mask(__m256i lo, __m256i hi) {
  return _mm256_permute4x64_epi64(_mm256_packs_epi32(lo, hi), 0xD8);
}

FAULTLINE_TARGET_INLINE("avx2") inline __m256i load(const std::int16_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

FAULTLINE_TARGET("avx2")
std::size_t suppress_avx2(std::uint8_t* map, const std::int16_t* dx, const std::int16_t* dy,
                          const std::int16_t* up, const std::int16_t* mid, const std::int16_t* down,
                          int low, int high, std::size_t n) {
  const __m256i lowv = _mm256_set1_epi16(static_cast<std::int16_t>(low));
  const __m256i highv = _mm256_set1_epi16(static_cast<std::int16_t>(high));
  const __m256i tan22 = _mm256_set1_epi32(kTan22);
  std::size_t x = 0;
  for (; x + 16 <= n; x += 16) {
    const __m256i m = load(mid + x + 1);
    const __m256i gx = load(dx + x), gy = load(dy + x);
    // m > a && m >= b  ==  (m > a) & !(b > m)
    const __m256i horizontal = _mm256_andnot_si256(_mm256_cmpgt_epi16(load(mid + x + 2), m),
                                                   _mm256_cmpgt_epi16(m, load(mid + x)));
    const __m256i vertical = _mm256_andnot_si256(_mm256_cmpgt_epi16(load(down + x + 1), m),
                                                 _mm256_cmpgt_epi16(m, load(up + x + 1)));
    const __m256i differ = _mm256_srai_epi16(_mm256_xor_si256(gx, gy), 15);
    const __m256i up_diag = _mm256_blendv_epi8(load(up + x), load(up + x + 2), differ);
    const __m256i down_diag = _mm256_blendv_epi8(load(down + x + 2), load(down + x), differ);
    const __m256i diagonal =
        _mm256_and_si256(_mm256_cmpgt_epi16(m, up_diag), _mm256_cmpgt_epi16(m, down_diag));
    const __m256i ax = _mm256_abs_epi16(gx), ay = _mm256_abs_epi16(gy);
    __m256i below22[2], above67[2];
    for (int h = 0; h < 2; ++h) {
      const __m128i ax16 = h ? _mm256_extracti128_si256(ax, 1) : _mm256_castsi256_si128(ax);
      const __m128i ay16 = h ? _mm256_extracti128_si256(ay, 1) : _mm256_castsi256_si128(ay);
      const __m256i ax32 = _mm256_cvtepi16_epi32(ax16);
      const __m256i ay32 = _mm256_slli_epi32(_mm256_cvtepi16_epi32(ay16), kShift);
      const __m256i tg22 = _mm256_mullo_epi32(ax32, tan22);
      const __m256i tg67 = _mm256_add_epi32(tg22, _mm256_slli_epi32(ax32, kShift + 1));
      below22[h] = _mm256_cmpgt_epi32(tg22, ay32);
      above67[h] = _mm256_cmpgt_epi32(ay32, tg67);
    }
    const __m256i peak = _mm256_blendv_epi8(
        _mm256_blendv_epi8(diagonal, vertical, packed_mask(above67[0], above67[1])), horizontal,
        packed_mask(below22[0], below22[1]));
    const __m256i candidate = _mm256_and_si256(peak, _mm256_cmpgt_epi16(m, lowv));
    const __m256i strong = _mm256_and_si256(_mm256_cmpgt_epi16(m, highv), _mm256_set1_epi16(2));
    const __m256i value = _mm256_blendv_epi8(_mm256_set1_epi16(1), strong, candidate);
    _mm_storeu_si128(
        reinterpret_cast<__m128i*>(map + x),
        _mm_packus_epi16(_mm256_castsi256_si128(value), _mm256_extracti128_si256(value, 1)));
  }
  return x;
}
#endif

void suppress_row(std::uint8_t* map, const std::int16_t* dx, const std::int16_t* dy,
                  const std::int16_t* up, const std::int16_t* mid, const std::int16_t* down,
                  int low, int high, std::size_t n, bool simd) {
  std::size_t x = 0;
#if FAULTLINE_X86_SIMD
  if (simd) x = suppress_avx2(map, dx, dy, up, mid, down, low, high, n);
#else
  (void)simd;
#endif
  for (; x < n; ++x) map[x] = suppress_value(dx, dy, up, mid, down, low, high, x);
}

// Row y of src, replicated one value each side, as int16.
void load_padded(std::int16_t* out, const cv::Mat& src, int y, std::size_t n) {
  const std::uint8_t* s = src.ptr<std::uint8_t>(y);
  for (std::size_t x = 0; x < n; ++x) out[x + 1] = s[x];
  out[0] = out[1];
  out[n + 1] = out[n];
}

// The hysteresis: every weak candidate (0) 8-connected to a strong pixel (2) through weak ones
// becomes strong. Started from the weak pixels next to a strong one (the first of every such
// path), found eight map values at a time (values 0, 1, 2: a byte is 0 where neither low bit is
// set); most candidates of a liquid field are strong, so this walks few pixels.
void hysteresis(std::vector<std::uint8_t>& map, std::size_t stride) {
  const auto s = static_cast<std::ptrdiff_t>(stride);
  const std::ptrdiff_t neighbours[8] = {-s - 1, -s, -s + 1, -1, 1, s - 1, s, s + 1};
  std::uint8_t* base = map.data();
  auto touches_strong = [&](const std::uint8_t* at) {
    for (const std::ptrdiff_t d : neighbours) {
      if (at[d] == 2) return true;
    }
    return false;
  };
  std::vector<std::uint8_t*> stack;
  auto flood = [&](std::uint8_t* seed) {
    *seed = 2;
    stack.push_back(seed);
    while (!stack.empty()) {
      std::uint8_t* at = stack.back();
      stack.pop_back();
      for (const std::ptrdiff_t d : neighbours) {
        if (at[d] == 0) {
          at[d] = 2;
          stack.push_back(at + d);
        }
      }
    }
  };
  // The frame (first and last row and column) is all 1: scan the inner part.
  const std::size_t first = stride, last = map.size() - stride;
  std::size_t i = first;
  for (; i + 8 <= last; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, base + i, 8);
    if ((~(word | (word >> 1)) & 0x0101010101010101ULL) == 0) continue;  // no 0 among the eight
    for (std::size_t j = i; j < i + 8; ++j) {
      if (base[j] == 0 && touches_strong(base + j)) flood(base + j);
    }
  }
  for (; i < last; ++i) {
    if (base[i] == 0 && touches_strong(base + i)) flood(base + i);
  }
}

}  // namespace

cv::Mat canny_l1(const cv::Mat& src, int low, int high, bool allow_simd) {
  cv::Mat edges;
  std::vector<std::uint8_t> map;
  canny_l1(src, low, high, edges, map, allow_simd);
  return edges;
}

void canny_l1(const cv::Mat& src, int low, int high, cv::Mat& edges, std::vector<std::uint8_t>& map,
              bool allow_simd) {
  const int rows = src.rows;
  const auto n = static_cast<std::size_t>(src.cols);
  const std::size_t stride = n + 2;
  // map: (rows + 2) x (n + 2), its frame 1 (no edge) so the hysteresis needs no bounds checks.
  map.assign(stride * static_cast<std::size_t>(rows + 2), 1);
  std::vector<std::int16_t> pixels(3 * stride), grads(6 * n), mags(3 * stride, 0);
  std::vector<std::int16_t> zero(stride, 0);
  auto pixel_row = [&](int y) { return pixels.data() + static_cast<std::size_t>(y % 3) * stride; };
  auto mag_row = [&](int y) {
    return y < 0 || y >= rows ? zero.data()
                              : mags.data() + static_cast<std::size_t>(y % 3) * stride;
  };
  auto dx_row = [&](int y) { return grads.data() + static_cast<std::size_t>(y % 3) * n; };
  auto dy_row = [&](int y) { return grads.data() + (3 + static_cast<std::size_t>(y % 3)) * n; };
  auto gradient = [&](int y) {  // needs pixel rows y - 1 .. y + 1 loaded (clamped)
    const std::int16_t* a = pixel_row(y > 0 ? y - 1 : 0);
    const std::int16_t* c = pixel_row(y + 1 < rows ? y + 1 : rows - 1);
    gradient_row(dx_row(y), dy_row(y), mag_row(y) + 1, a, pixel_row(y), c, n);
  };
  const bool simd = allow_simd && common::cpu_has_avx2();
  if (rows > 0) {
    load_padded(pixel_row(0), src, 0, n);
    if (rows > 1) load_padded(pixel_row(1), src, 1, n);
    gradient(0);
  }
  for (int y = 0; y < rows; ++y) {
    if (y + 1 < rows) {
      if (y + 2 < rows) load_padded(pixel_row(y + 2), src, y + 2, n);
      gradient(y + 1);
    }
    std::uint8_t* m = map.data() + static_cast<std::size_t>(y + 1) * stride + 1;
    suppress_row(m, dx_row(y), dy_row(y), mag_row(y - 1), mag_row(y), mag_row(y + 1), low, high, n,
                 simd);
  }
  hysteresis(map, stride);
  edges.create(src.size(), CV_8U);
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* m = map.data() + static_cast<std::size_t>(y + 1) * stride + 1;
    std::uint8_t* e = edges.ptr<std::uint8_t>(y);
    for (std::size_t x = 0; x < n; ++x) e[x] = static_cast<std::uint8_t>((m[x] >> 1) * 255);
  }
}

}  // namespace faultline::corruption
