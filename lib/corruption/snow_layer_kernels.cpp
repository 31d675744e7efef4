// Snow layer loops: corner-aligned zoom, threshold, layer blur and quantisation. The AVX2 bodies
// run whole blocks and the scalar bodies (same arithmetic, same rounding) the rest.
#include <algorithm>
#include <cmath>
#include <vector>

#include "common/simd.hpp"
#include "corruption/snow_kernels.hpp"

namespace faultline::corruption::snow_kernels {

bool use_avx2(bool allow_simd) {
#if FAULTLINE_X86_SIMD
  return allow_simd && common::cpu_has_avx2();
#else
  (void)allow_simd;
  return false;
#endif
}

namespace {

#if FAULTLINE_X86_SIMD

FAULTLINE_TARGET("avx2")
void column_zoom_avx2(const float* src, float* dst, int n_out, const std::int32_t* base,
                      const std::int32_t* rel0, const std::int32_t* rel1, const float* w,
                      const float* one_minus_w) {
  for (int blk = 0; blk * 8 < n_out; ++blk) {
    if (base[blk] < 0) continue;  // left to the scalar body
    const int o = 8 * blk;
    const __m256 v = _mm256_loadu_ps(src + base[blk]);
    const __m256 a =
        _mm256_permutevar8x32_ps(v, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(rel0 + o)));
    const __m256 b =
        _mm256_permutevar8x32_ps(v, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(rel1 + o)));
    const __m256 r = _mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(one_minus_w + o), a),
                                   _mm256_mul_ps(_mm256_loadu_ps(w + o), b));
    _mm256_storeu_ps(dst + o, r);
  }
}

FAULTLINE_TARGET("avx2")
void column_zoom64_avx2(const double* src, double threshold, double* dst, int blocks,
                        const std::int32_t* base, const std::int32_t* idx0,
                        const std::int32_t* idx1, const double* w) {
  const __m256d one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd(),
                thr = _mm256_set1_pd(threshold);
  for (int blk = 0; blk < blocks; ++blk) {
    if (base[blk] < 0) continue;  // left to the scalar body
    const int o = 4 * blk;
    // Four doubles as eight float lanes: moving lane pairs (2r, 2r + 1) moves double r.
    const __m256 v = _mm256_castpd_ps(_mm256_loadu_pd(src + base[blk]));
    const __m256d a = _mm256_castps_pd(_mm256_permutevar8x32_ps(
        v, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(idx0 + 2 * o))));
    const __m256d b = _mm256_castps_pd(_mm256_permutevar8x32_ps(
        v, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(idx1 + 2 * o))));
    const __m256d wv = _mm256_loadu_pd(w + o);
    __m256d t = _mm256_add_pd(_mm256_mul_pd(_mm256_sub_pd(one, wv), a), _mm256_mul_pd(wv, b));
    t = _mm256_andnot_pd(_mm256_cmp_pd(t, thr, _CMP_LT_OQ), t);
    _mm256_storeu_pd(dst + o, _mm256_min_pd(_mm256_max_pd(t, zero), one));
  }
}

// Whole blocks of 32 outputs, sums kept in registers across all taps; returns how many outputs it
// wrote.
FAULTLINE_TARGET("avx2")
std::size_t blur_quantise64_avx2(const double* const* rows, const double* weights, int taps,
                                 std::uint8_t* dst, std::size_t n) {
  constexpr int kVectors = 8;
  const __m256d k255 = _mm256_set1_pd(255.0);
  std::size_t j0 = 0;
  for (; j0 + 4 * kVectors <= n; j0 += 4 * kVectors) {
    __m256d s[kVectors];
    for (auto& v : s) v = _mm256_setzero_pd();
    for (int i = 0; i < taps; ++i) {
      const double* r = rows[i] + j0;
      const __m256d k = _mm256_set1_pd(weights[i]);
      for (int v = 0; v < kVectors; ++v)
        s[v] = _mm256_add_pd(s[v], _mm256_mul_pd(k, _mm256_loadu_pd(r + 4 * v)));
    }
    __m128i q[kVectors];
    for (int v = 0; v < kVectors; ++v) {
      q[v] = _mm256_cvttpd_epi32(_mm256_round_pd(_mm256_mul_pd(s[v], k255),
                                                 _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
    }
    for (int v = 0; v < kVectors; v += 4) {
      const __m128i w0 = _mm_packus_epi32(q[v], q[v + 1]),
                    w1 = _mm_packus_epi32(q[v + 2], q[v + 3]);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + j0 + 4 * v), _mm_packus_epi16(w0, w1));
    }
  }
  return j0;
}

// Eight float32 sums -> eight bytes, rounded half to even as quantise_value does.
FAULTLINE_TARGET("avx2") inline __m128i quantise8(__m256 s) {
  const __m256 k255 = _mm256_set1_ps(255.0f), magic = _mm256_set1_ps(12582912.0f);
  const __m256 r = _mm256_sub_ps(_mm256_add_ps(_mm256_mul_ps(s, k255), magic), magic);
  const __m256i q = _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(r, _mm256_setzero_ps()), k255));
  const __m128i words = _mm_packus_epi32(_mm256_castsi256_si128(q), _mm256_extracti128_si256(q, 1));
  return _mm_packus_epi16(words, words);
}

// Sixteen 16-bit layer sums (65535 = 1.0) -> bytes round(s / 257) (= round(255 * s / 65535));
// `bias` (+128 for the rounding, plus half an LSB per tap for the truncating products) is added
// with saturation.
FAULTLINE_TARGET("avx2") inline __m256i quantise16(__m256i s, __m256i bias) {
  const __m256i t = _mm256_adds_epu16(s, bias);
  return _mm256_srli_epi16(_mm256_sub_epi16(t, _mm256_srli_epi16(t, 8)), 8);
}

// dst[j] = quantise16(sum over taps of mulhi(w[i], src[i][j]), saturating) for j < n (src readable
// up to n rounded up to 16): blocks of 128 columns, then single vectors, sums in registers across
// all taps.
FAULTLINE_TARGET("avx2")
void blur_row_u16_avx2(const std::uint16_t* const* src, const std::uint16_t* w, int taps,
                       std::uint16_t bias, std::uint8_t* dst, int n) {
  constexpr int kVectors = 8, kBlock = 16 * kVectors;
  const __m256i biasv = _mm256_set1_epi16(static_cast<short>(bias));
  int j0 = 0;
  for (; j0 + kBlock <= n; j0 += kBlock) {
    __m256i s[kVectors];
    for (auto& v : s) v = _mm256_setzero_si256();
    for (int i = 0; i < taps; ++i) {
      const std::uint16_t* r = src[i] + j0;
      const __m256i k = _mm256_set1_epi16(static_cast<short>(w[i]));
      for (int v = 0; v < kVectors; ++v) {
        const __m256i x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(r + 16 * v));
        s[v] = _mm256_adds_epu16(s[v], _mm256_mulhi_epu16(k, x));
      }
    }
    for (int v = 0; v < kVectors; v += 2) {
      const __m256i bytes =
          _mm256_packus_epi16(quantise16(s[v], biasv), quantise16(s[v + 1], biasv));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + j0 + 16 * v),
                          _mm256_permute4x64_epi64(bytes, 0xD8));
    }
  }
  for (; j0 < n; j0 += 16) {
    __m256i s = _mm256_setzero_si256();
    for (int i = 0; i < taps; ++i) {
      const __m256i x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src[i] + j0));
      s = _mm256_adds_epu16(s, _mm256_mulhi_epu16(_mm256_set1_epi16(static_cast<short>(w[i])), x));
    }
    const __m256i q = quantise16(s, biasv);
    const __m128i bytes =
        _mm_packus_epi16(_mm256_castsi256_si128(q), _mm256_extracti128_si256(q, 1));
    if (j0 + 16 <= n) {
      _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + j0), bytes);
    } else {
      alignas(16) std::uint8_t tail[16];
      _mm_store_si128(reinterpret_cast<__m128i*>(tail), bytes);
      std::copy(tail, tail + (n - j0), dst + j0);
    }
  }
}

// lerp_threshold_u16 in whole blocks of 16; returns how many values it wrote.
FAULTLINE_TARGET("avx2")
int lerp_threshold_u16_avx2(const float* a, const float* b, float w, float threshold,
                            std::uint16_t* dst, int n) {
  const __m256 w0 = _mm256_set1_ps(1.0f - w), w1 = _mm256_set1_ps(w),
               thr = _mm256_set1_ps(threshold);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), k = _mm256_set1_ps(65535.0f);
  int x = 0;
  for (; x + 16 <= n; x += 16) {
    __m256i q[2];
    for (int h = 0; h < 2; ++h) {
      const int o = x + 8 * h;
      __m256 v = _mm256_add_ps(_mm256_mul_ps(w0, _mm256_loadu_ps(a + o)),
                               _mm256_mul_ps(w1, _mm256_loadu_ps(b + o)));
      v = _mm256_andnot_ps(_mm256_cmp_ps(v, thr, _CMP_LT_OQ), v);
      q[h] = _mm256_cvtps_epi32(_mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(v, zero), one), k));
    }
    const __m256i words = _mm256_permute4x64_epi64(_mm256_packus_epi32(q[0], q[1]), 0xD8);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + x), words);
  }
  return x;
}

#endif  // FAULTLINE_X86_SIMD

inline std::uint8_t quantise_value(float v) {
  constexpr float kMagic = 12582912.0f;  // adding and removing 1.5 * 2^23 rounds half to even
  const float r = (v * 255.0f + kMagic) - kMagic;
  return static_cast<std::uint8_t>(static_cast<int>(std::min(std::max(r, 0.0f), 255.0f)));
}

inline std::uint8_t quantise_u16(std::uint32_t s, std::uint32_t bias) {
  const std::uint32_t t = std::min<std::uint32_t>(s + bias, 65535);
  return static_cast<std::uint8_t>((t - (t >> 8)) >> 8);
}

void blur_row_u16_scalar(const std::uint16_t* const* src, const std::uint16_t* w, int taps,
                         std::uint16_t bias, std::uint8_t* dst, int n) {
  for (int j = 0; j < n; ++j) {
    std::uint32_t s = 0;
    for (int i = 0; i < taps; ++i)
      s = std::min<std::uint32_t>(65535, s + ((std::uint32_t{w[i]} * src[i][j]) >> 16));
    dst[j] = quantise_u16(s, bias);
  }
}

}  // namespace

ZoomAxis zoom_axis(int n_in, int n_out) {
  ZoomAxis m;
  const auto n = static_cast<std::size_t>(n_out);
  m.i0.resize(n);
  m.i1.resize(n);
  m.w.resize(n);
  m.one_minus_w.resize(n);
  const double ratio =
      n_out > 1 ? static_cast<double>(n_in - 1) / static_cast<double>(n_out - 1) : 0.0;
  for (std::size_t o = 0; o < n; ++o) {
    const double p = static_cast<double>(o) * ratio;
    const int i = std::clamp(static_cast<int>(std::floor(p)), 0, n_in - 1);
    m.i0[o] = i;
    m.i1[o] = std::min(i + 1, n_in - 1);
    m.w[o] = static_cast<float>(p - i);
    m.one_minus_w[o] = 1.0f - m.w[o];
  }
  return m;
}

ColumnZoom::ColumnZoom(int n_in, int n_out)
    : n_in_(n_in), n_out_(n_out), map_(zoom_axis(n_in, n_out)) {
  const int blocks = n_out / 8;  // whole blocks only; the tail is scalar
  base_.assign(static_cast<std::size_t>(blocks), -1);
  rel0_.assign(static_cast<std::size_t>(n_out), 0);
  rel1_.assign(static_cast<std::size_t>(n_out), 0);
  for (int blk = 0; blk < blocks; ++blk) {
    const int base = map_.i0[static_cast<std::size_t>(8 * blk)];
    const int last = map_.i1[static_cast<std::size_t>(8 * blk + 7)];
    if (last - base > 7 || base + 8 > n_in) continue;  // outside one 8-float window: scalar
    base_[static_cast<std::size_t>(blk)] = base;
    for (int o = 8 * blk; o < 8 * blk + 8; ++o) {
      rel0_[static_cast<std::size_t>(o)] = map_.i0[static_cast<std::size_t>(o)] - base;
      rel1_[static_cast<std::size_t>(o)] = map_.i1[static_cast<std::size_t>(o)] - base;
    }
  }
}

void ColumnZoom::run(const float* src, float* dst, bool allow_simd) const {
  auto scalar = [&](int o0, int o1) {
    for (int o = o0; o < o1; ++o) {
      const auto u = static_cast<std::size_t>(o);
      dst[o] = map_.one_minus_w[u] * src[map_.i0[u]] + map_.w[u] * src[map_.i1[u]];
    }
  };
  const int blocks = static_cast<int>(base_.size());
  if (use_avx2(allow_simd)) {
#if FAULTLINE_X86_SIMD
    column_zoom_avx2(src, dst, blocks * 8, base_.data(), rel0_.data(), rel1_.data(), map_.w.data(),
                     map_.one_minus_w.data());
#endif
    for (int blk = 0; blk < blocks; ++blk) {
      if (base_[static_cast<std::size_t>(blk)] < 0) scalar(8 * blk, 8 * blk + 8);
    }
    scalar(8 * blocks, n_out_);
  } else {
    scalar(0, n_out_);
  }
}

void lerp_threshold_u16(const float* a, const float* b, float w, float threshold,
                        std::uint16_t* dst, int n, bool allow_simd) {
  int x = 0;
#if FAULTLINE_X86_SIMD
  if (use_avx2(allow_simd)) x = lerp_threshold_u16_avx2(a, b, w, threshold, dst, n);
#else
  (void)allow_simd;
#endif
  const float w0 = 1.0f - w;
  for (; x < n; ++x) {
    float v = w0 * a[x] + w * b[x];
    v = v < threshold ? 0.0f : v;
    dst[x] =
        static_cast<std::uint16_t>(std::nearbyint(std::min(std::max(v, 0.0f), 1.0f) * 65535.0f));
  }
}

// Element-wise float32 loop: vectorising it does not change any value, so the clones need no scalar
// twin. Adding and removing 1.5 * 2^23 rounds half to even in the default rounding mode (nearbyint
// without a libm call).
FAULTLINE_CLONES("avx2")
void quantise_row(const float* __restrict src, std::uint8_t* __restrict dst, int n) {
  for (int x = 0; x < n; ++x) dst[x] = quantise_value(src[x]);
}

void blur_quantise(const LayerRowMaker& make_row, int lh, int lw, const int* dx, const int* dy,
                   const float* w, int taps, std::uint8_t* dst, std::size_t dst_stride, int rows,
                   int cols, bool allow_simd) {
  const bool simd = use_avx2(allow_simd);
  // Taps whose 16-bit weight is 0 add exactly 0 (the Gaussian tails of the sigma-4 kernels: 6 of
  // 25), so they are dropped; the rounding bias still counts every tap.
  int pad = 0, dy_min = 0, dy_max = 0;  // tap 0 is (0, 0)
  std::vector<std::uint16_t> w16;
  std::vector<int> tap_dx, tap_dy;
  for (int i = 0; i < taps; ++i) {
    const auto wi = static_cast<std::uint16_t>(std::min(65535L, std::lround(w[i] * 65536.0)));
    if (wi == 0) continue;
    w16.push_back(wi), tap_dx.push_back(dx[i]), tap_dy.push_back(dy[i]);
    pad = std::max(pad, std::abs(dx[i]));
    dy_min = std::min(dy_min, dy[i]), dy_max = std::max(dy_max, dy[i]);
  }
  const auto bias = static_cast<std::uint16_t>(128 + taps / 2);
  taps = static_cast<int>(w16.size());
  dx = tap_dx.data(), dy = tap_dy.data();
  // Ring slot r & (ring_rows - 1) holds layer row r, edge-padded by `pad`, and 16 spare values so
  // the last output vector's lanes past cols read inside the row. The ring (~110 KB at 1600
  // columns) stays in L2, where the whole float layer (~6 MB) did not.
  int ring_rows = 1;
  while (ring_rows < dy_max - dy_min + 1) ring_rows *= 2;
  const int stride = lw + 2 * pad, ring_stride = (stride + 16 + 15) / 16 * 16;
  thread_local std::vector<std::uint16_t> ring;
  ring.assign(static_cast<std::size_t>(ring_rows) * static_cast<std::size_t>(ring_stride), 0);
  auto slot = [&](int r) { return static_cast<std::size_t>(r & (ring_rows - 1)); };
  std::vector<const std::uint16_t*> src(static_cast<std::size_t>(taps));
  int made = 0;  // layer rows [0, made) have been made
  for (int y = 0; y < rows; ++y) {
    for (const int last = std::clamp(y - dy_min, 0, lh - 1); made <= last; ++made) {
      std::uint16_t* d = ring.data() + slot(made) * static_cast<std::size_t>(ring_stride);
      make_row(made, d + pad);
      std::fill(d, d + pad, d[pad]);
      std::fill(d + pad + lw, d + stride, d[pad + lw - 1]);
    }
    for (int i = 0; i < taps; ++i) {
      const int r = std::clamp(y - dy[i], 0, lh - 1);
      src[static_cast<std::size_t>(i)] =
          ring.data() + slot(r) * static_cast<std::size_t>(ring_stride) + (pad - dx[i]);
    }
    std::uint8_t* d = dst + static_cast<std::size_t>(y) * dst_stride;
    if (!simd) {
      blur_row_u16_scalar(src.data(), w16.data(), taps, bias, d, cols);
      continue;
    }
#if FAULTLINE_X86_SIMD
    blur_row_u16_avx2(src.data(), w16.data(), taps, bias, d, cols);
#endif
  }
}

FAULTLINE_CLONES("avx2")
void lerp_row64(const double* __restrict a, const double* __restrict b, double w,
                double* __restrict dst, int n) {
  const double w0 = 1.0 - w;
  for (int x = 0; x < n; ++x) dst[x] = w0 * a[x] + w * b[x];
}

ColumnZoom64::ColumnZoom64(int n_in, int n_out) : n_in_(n_in), n_out_(n_out) {
  const auto n = static_cast<std::size_t>(n_out);
  i0_.resize(n);
  i1_.resize(n);
  w_.resize(n);
  const double ratio =
      n_out > 1 ? static_cast<double>(n_in - 1) / static_cast<double>(n_out - 1) : 0.0;
  for (std::size_t o = 0; o < n; ++o) {
    const double p = static_cast<double>(o) * ratio;
    const int i = std::clamp(static_cast<int>(std::floor(p)), 0, n_in - 1);
    i0_[o] = i;
    i1_[o] = std::min(i + 1, n_in - 1);
    w_[o] = p - i;
  }
  const int blocks = n_out / 4;
  base_.assign(static_cast<std::size_t>(blocks), -1);
  idx0_.assign(2 * n, 0);
  idx1_.assign(2 * n, 0);
  for (int blk = 0; blk < blocks; ++blk) {
    const int base = i0_[static_cast<std::size_t>(4 * blk)];
    if (i1_[static_cast<std::size_t>(4 * blk + 3)] - base > 3 || base + 4 > n_in) continue;
    base_[static_cast<std::size_t>(blk)] = base;
    for (int o = 4 * blk; o < 4 * blk + 4; ++o) {
      const auto u = static_cast<std::size_t>(o);
      idx0_[2 * u] = 2 * (i0_[u] - base), idx0_[2 * u + 1] = 2 * (i0_[u] - base) + 1;
      idx1_[2 * u] = 2 * (i1_[u] - base), idx1_[2 * u + 1] = 2 * (i1_[u] - base) + 1;
    }
  }
}

void ColumnZoom64::run(const double* src, double threshold, double* dst, bool allow_simd) const {
  auto scalar = [&](int o0, int o1) {
    for (int o = o0; o < o1; ++o) {
      const auto u = static_cast<std::size_t>(o);
      const double w = w_[u];
      double v = (1.0 - w) * src[i0_[u]] + w * src[i1_[u]];
      if (v < threshold) v = 0.0;
      dst[o] = std::min(std::max(v, 0.0), 1.0);
    }
  };
  const int blocks = static_cast<int>(base_.size());
  if (use_avx2(allow_simd)) {
#if FAULTLINE_X86_SIMD
    column_zoom64_avx2(src, threshold, dst, blocks, base_.data(), idx0_.data(), idx1_.data(),
                       w_.data());
#endif
    for (int blk = 0; blk < blocks; ++blk) {
      if (base_[static_cast<std::size_t>(blk)] < 0) scalar(4 * blk, 4 * blk + 4);
    }
    scalar(4 * blocks, n_out_);
  } else {
    scalar(0, n_out_);
  }
}

void blur_quantise64(const double* const* rows, const double* weights, int taps, std::uint8_t* dst,
                     std::size_t n, bool allow_simd) {
  std::size_t j = 0;
#if FAULTLINE_X86_SIMD
  if (use_avx2(allow_simd)) j = blur_quantise64_avx2(rows, weights, taps, dst, n);
#else
  (void)allow_simd;
#endif
  for (; j < n; ++j) {
    double s = 0.0;
    for (int i = 0; i < taps; ++i) s += weights[i] * rows[i][j];
    dst[j] = static_cast<std::uint8_t>(std::nearbyint(s * 255.0));
  }
}

}  // namespace faultline::corruption::snow_kernels
