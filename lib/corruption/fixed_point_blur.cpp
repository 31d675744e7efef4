// Fixed-point separable blur: Q15 weights, exact 32-bit sums, one rounding between the passes.
#include "corruption/fixed_point_blur.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/simd.hpp"
#include "corruption/ndimage.hpp"

namespace faultline::corruption {

namespace {

// The column pass's Q15 sums become Q6 (at most 255 * 64 = 16 320, so a pair of them still fits
// a signed 16-bit lane); the row pass's Q6 x Q15 sums (< 2^30) are shifted by 6 + 15.
constexpr int kMidShift = 9;
constexpr int kOutShift = 21;
// Vector paths up to this radius (17 pairs of terms); larger kernels take the portable loops.
constexpr int kMaxVectorRadius = 32;

// The portable loops, from element `from` on (the vector paths' tails). Integer sums in any order
// are the same, so the two paths agree byte for byte.
void column_pass(std::int16_t* mid, const std::uint8_t* const* rows, const std::int16_t* w, int r,
                 std::size_t from, std::size_t n) {
  for (std::size_t i = from; i < n; ++i) {
    std::int32_t s = w[0] * rows[r][i];
    for (int k = 1; k <= r; ++k) s += w[k] * (rows[r - k][i] + rows[r + k][i]);
    mid[i] = static_cast<std::int16_t>((s + (1 << (kMidShift - 1))) >> kMidShift);
  }
}

// Sums whose fraction is below this (1/512 of a level) count as landing on their integer.
constexpr std::int32_t kOnLevel = 1 << (kOutShift - 9);

std::uint8_t store(std::int32_t s, const std::uint8_t* flat) {
  const auto v = static_cast<std::uint8_t>(std::min(s >> kOutShift, 255));
  return flat && (s & ((1 << kOutShift) - 1)) < kOnLevel ? flat[v] : v;
}

void row_pass(std::uint8_t* out, const std::int16_t* mid, std::ptrdiff_t step,
              const std::int16_t* w, int r, const std::uint8_t* flat, std::size_t from,
              std::size_t n) {
  for (std::size_t i = from; i < n; ++i) {
    const std::int16_t* c = mid + i;
    std::int32_t s = w[0] * c[0];
    for (int k = 1; k <= r; ++k) s += w[k] * (c[-step * k] + c[step * k]);
    out[i] = store(s, flat);
  }
}

struct PairWeights;

// One output row's inputs: the 2 r + 1 source rows, the column pass's row (r pixels of border each
// side), the output row.
struct RowJob {
  const std::uint8_t* const* rows;
  std::int16_t* mid;
  std::uint8_t* out;
  std::ptrdiff_t step;  // channels
  std::size_t n;        // values per row
  int radius;
  const std::int16_t* weight;
  const PairWeights* pairs;
  const std::uint8_t* flat;  // or nullptr
};

// The first and last pixel repeated r times beyond the row.
void fill_border(const RowJob& job) {
  std::int16_t* last = job.mid + static_cast<std::ptrdiff_t>(job.n) - job.step;
  for (std::ptrdiff_t p = 1; p <= job.radius; ++p) {
    std::copy(job.mid, job.mid + job.step, job.mid - p * job.step);
    std::copy(last, last + job.step, last + p * job.step);
  }
}

void blur_row(const RowJob& job) {
  column_pass(job.mid, job.rows, job.weight, job.radius, 0, job.n);
  fill_border(job);
  row_pass(job.out, job.mid, job.step, job.weight, job.radius, job.flat, 0, job.n);
}

using BlurRow = void (*)(const RowJob&);

#if FAULTLINE_X86_SIMD
// The terms (centre, then each symmetric pair's sum) two at a time: interleaved 16-bit lanes times
// a (w_a, w_b) pair of weights in one madd. unpacklo/hi and the final packs work within 128-bit
// lanes alike, so the packed results come out in element order.
struct PairWeights {
  std::int32_t w[kMaxVectorRadius / 2 + 1] = {};  // w_a in the low half, w_b in the high one
  int pairs = 0;
};

PairWeights pair_weights(const std::int16_t* w, int r) {
  PairWeights p;
  for (int t = 0; t <= r; t += 2) {
    const auto lo = static_cast<std::uint16_t>(w[t]);
    const auto hi = static_cast<std::uint16_t>(t + 1 <= r ? w[t + 1] : 0);
    p.w[p.pairs++] = static_cast<std::int32_t>(static_cast<std::uint32_t>(hi) << 16 | lo);
  }
  return p;
}

FAULTLINE_TARGET_INLINE("avx2") inline __m256i widen(const std::uint8_t* p) {
  return _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
}

FAULTLINE_TARGET_INLINE("avx2") inline __m256i load16(const std::int16_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

// Term t of the column pass at element j: the centre row, or rows r - t and r + t summed.
FAULTLINE_TARGET_INLINE("avx2")
inline __m256i column_term(const std::uint8_t* const* rows, int r, int t, std::size_t j) {
  if (t == 0) return widen(rows[r] + j);
  if (t > r) return _mm256_setzero_si256();
  return _mm256_add_epi16(widen(rows[r - t] + j), widen(rows[r + t] + j));
}

// Term t of the row pass around c: the centre, or the values t pixels left and right summed.
FAULTLINE_TARGET_INLINE("avx2")
inline __m256i row_term(const std::int16_t* c, std::ptrdiff_t step, int r, int t) {
  if (t == 0) return load16(c);
  if (t > r) return _mm256_setzero_si256();
  return _mm256_add_epi16(load16(c - step * t), load16(c + step * t));
}

FAULTLINE_TARGET_INLINE("avx2")
inline void madd_pair(__m256i& lo, __m256i& hi, __m256i a, __m256i b, std::int32_t w) {
  const __m256i wv = _mm256_set1_epi32(w);
  lo = _mm256_add_epi32(lo, _mm256_madd_epi16(_mm256_unpacklo_epi16(a, b), wv));
  hi = _mm256_add_epi32(hi, _mm256_madd_epi16(_mm256_unpackhi_epi16(a, b), wv));
}

// The passes with the radius a constant (R > 0) or read at run time (R = 0): constant radii
// unroll the taps and keep every row pointer in a register.
template <int R>
FAULTLINE_TARGET_INLINE("avx2")
inline std::size_t column_pass_avx2(std::int16_t* mid, const std::uint8_t* const* rows,
                                    const PairWeights& pw, int radius, std::size_t n) {
  const int r = R > 0 ? R : radius;
  const int pairs = R > 0 ? R / 2 + 1 : pw.pairs;
  const __m256i half = _mm256_set1_epi32(1 << (kMidShift - 1));
  std::size_t j = 0;
  for (; j + 16 <= n; j += 16) {
    __m256i lo = half, hi = half;
    for (int p = 0; p < pairs; ++p) {
      madd_pair(lo, hi, column_term(rows, r, 2 * p, j), column_term(rows, r, 2 * p + 1, j),
                pw.w[p]);
    }
    lo = _mm256_srai_epi32(lo, kMidShift);
    hi = _mm256_srai_epi32(hi, kMidShift);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(mid + j), _mm256_packs_epi32(lo, hi));
  }
  return j;
}

// The values of a 16-value block whose sums land on their integer (see kOnLevel) become flat[v].
// Their lanes come from lo (values 0-3 and 8-11) and hi (4-7 and 12-15), as madd_pair left them.
FAULTLINE_TARGET_INLINE("avx2")
inline void apply_flat(std::uint8_t* out, __m256i lo, __m256i hi, const std::uint8_t* flat) {
  const __m256i fraction = _mm256_set1_epi32((1 << kOutShift) - 1);
  const __m256i on_level = _mm256_set1_epi32(kOnLevel);
  const __m256i lo_on = _mm256_cmpgt_epi32(on_level, _mm256_and_si256(lo, fraction));
  const __m256i hi_on = _mm256_cmpgt_epi32(on_level, _mm256_and_si256(hi, fraction));
  const int lo_bits = _mm256_movemask_ps(_mm256_castsi256_ps(lo_on));
  const int hi_bits = _mm256_movemask_ps(_mm256_castsi256_ps(hi_on));
  if ((lo_bits | hi_bits) == 0) return;
  static constexpr int kLoValue[8] = {0, 1, 2, 3, 8, 9, 10, 11};
  for (int b = 0; b < 8; ++b) {
    if (lo_bits >> b & 1) out[kLoValue[b]] = flat[out[kLoValue[b]]];
    if (hi_bits >> b & 1) out[kLoValue[b] + 4] = flat[out[kLoValue[b] + 4]];
  }
}

template <int R>
FAULTLINE_TARGET_INLINE("avx2")
inline std::size_t
    row_pass_avx2(std::uint8_t* out, const std::int16_t* mid, std::ptrdiff_t step,
                  const PairWeights& pw, int radius, const std::uint8_t* flat, std::size_t n) {
  const int r = R > 0 ? R : radius;
  const int pairs = R > 0 ? R / 2 + 1 : pw.pairs;
  std::size_t j = 0;
  for (; j + 16 <= n; j += 16) {
    const std::int16_t* c = mid + j;
    __m256i lo = _mm256_setzero_si256(), hi = _mm256_setzero_si256();
    for (int p = 0; p < pairs; ++p) {
      madd_pair(lo, hi, row_term(c, step, r, 2 * p), row_term(c, step, r, 2 * p + 1), pw.w[p]);
    }
    const __m256i words =
        _mm256_packs_epi32(_mm256_srai_epi32(lo, kOutShift), _mm256_srai_epi32(hi, kOutShift));
    // Bytes 0-7 in the low lane and 8-15 in the high one (each twice): gather quadwords 0 and 2.
    const __m256i bytes = _mm256_permute4x64_epi64(_mm256_packus_epi16(words, words), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + j), _mm256_castsi256_si128(bytes));
    if (flat) apply_flat(out + j, lo, hi, flat);
  }
  return j;
}

// One output row: the column pass into `mid`, its border, the row pass (the portable loops finish
// what the vector loops leave).
template <int R>
FAULTLINE_TARGET("avx2")
void blur_row_avx2(const RowJob& job) {
  const std::size_t n = job.n;
  std::size_t j = column_pass_avx2<R>(job.mid, job.rows, *job.pairs, job.radius, n);
  column_pass(job.mid, job.rows, job.weight, job.radius, j, n);
  fill_border(job);
  j = row_pass_avx2<R>(job.out, job.mid, job.step, *job.pairs, job.radius, job.flat, n);
  row_pass(job.out, job.mid, job.step, job.weight, job.radius, job.flat, j, n);
}

BlurRow blur_row_for(int radius) {
  switch (radius) {
    case 1:
      return blur_row_avx2<1>;
    case 2:
      return blur_row_avx2<2>;
    case 3:
      return blur_row_avx2<3>;
    case 4:
      return blur_row_avx2<4>;
    case 5:
      return blur_row_avx2<5>;
    case 6:
      return blur_row_avx2<6>;
    case 7:
      return blur_row_avx2<7>;
    case 8:
      return blur_row_avx2<8>;
    default:
      return blur_row_avx2<0>;
  }
}
#endif

}  // namespace

FixedPointKernel fixed_point_kernel(const std::vector<double>& half, int bits) {
  if (half.empty()) throw std::invalid_argument("fixed_point_kernel: empty kernel");
  if (bits < 1 || bits > 15) throw std::invalid_argument("fixed_point_kernel: bits must be 1..15");
  const int one = 1 << bits;
  FixedPointKernel k;
  k.radius = static_cast<int>(half.size()) - 1;
  k.weight.resize(half.size());
  int sides = 0;
  for (std::size_t i = 1; i < half.size(); ++i) {
    k.weight[i] = static_cast<std::int16_t>(std::lround(std::ldexp(half[i], bits)));
    sides += 2 * k.weight[i];
  }
  const int centre = one - sides;
  if (centre < 0 || centre >= one) {
    throw std::invalid_argument("fixed_point_kernel: the centre weight must be in [0, 1)");
  }
  k.weight[0] = static_cast<std::int16_t>(centre);
  return k;
}

FixedPointKernel fixed_point_gaussian(double sigma, int radius) {
  return fixed_point_kernel(nd::gaussian_kernel(sigma, radius));
}

void fixed_point_blur(const cv::Mat& in, const FixedPointKernel& k, cv::Mat& out,
                      const std::array<std::uint8_t, 256>* flat) {
  CV_Assert(in.depth() == CV_8U && in.dims == 2);
  if (!in.empty() && out.data == in.data) {  // the column pass reads rows the output replaced
    cv::Mat separate;
    fixed_point_blur(in, k, separate, flat);
    out = separate;
    return;
  }
  out.create(in.size(), in.type());
  if (in.empty()) return;
  const int r = k.radius, rows = in.rows;
  const std::ptrdiff_t step = in.channels();
  const auto n = static_cast<std::size_t>(in.cols) * static_cast<std::size_t>(step);
  std::vector<const std::uint8_t*> taps(static_cast<std::size_t>(2 * r + 1));
  std::vector<std::int16_t> line(n + 2 * static_cast<std::size_t>(r * step));
  RowJob job{taps.data(), line.data() + r * step,       nullptr, step, n, r, k.weight.data(),
             nullptr,     flat ? flat->data() : nullptr};
  BlurRow blur = blur_row;
#if FAULTLINE_X86_SIMD
  PairWeights pw;
  if (common::cpu_has_avx2() && r <= kMaxVectorRadius) {
    pw = pair_weights(k.weight.data(), r);
    job.pairs = &pw;
    blur = blur_row_for(r);
  }
#endif
  for (int y = 0; y < rows; ++y) {
    for (int t = -r; t <= r; ++t) {
      taps[static_cast<std::size_t>(t + r)] = in.ptr<std::uint8_t>(std::clamp(y + t, 0, rows - 1));
    }
    job.out = out.ptr<std::uint8_t>(y);
    blur(job);
  }
}

}  // namespace faultline::corruption
