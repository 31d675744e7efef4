// Motion blur as shifted multiply-adds over a horizontally edge-padded copy, one output row at a
// time.
#include "corruption/motion_blur.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <type_traits>
#include <vector>

#include "corruption/motion_kernel.hpp"
#include "corruption/simd_kernels.hpp"

namespace faultline::corruption {

std::vector<TapOffset> motion_offsets(double angle_deg, int width) {
  const double rad = angle_deg * (M_PI / 180.0);
  const double p0 = width * std::sin(rad);
  const double p1 = width * std::cos(rad);
  const double h = std::hypot(p0, p1);
  std::vector<TapOffset> out(static_cast<std::size_t>(width));
  for (int i = 0; i < width; ++i) {
    out[static_cast<std::size_t>(i)].dy = -static_cast<int>(std::ceil((i * p0) / h - 0.5));
    out[static_cast<std::size_t>(i)].dx = -static_cast<int>(std::ceil((i * p1) / h - 0.5));
  }
  return out;
}

int usable_taps(const std::vector<TapOffset>& offsets, int rows, int cols) {
  int n = 0;
  for (const auto& o : offsets) {
    if (std::abs(o.dy) >= rows || std::abs(o.dx) >= cols) break;
    ++n;
  }
  return n;
}

MotionBlurParams motion_blur_params(int severity) {
  static constexpr MotionBlurParams kTable[] = {{10, 3}, {15, 5}, {15, 8}, {15, 12}, {20, 15}};
  return kTable[std::clamp(severity, 1, 5) - 1];
}

namespace {

// Runs acc(row) = sum_i k_i * src(clamp(y - dy_i), clamp(x - dx_i)) for every row y and hands each
// finished accumulator row to `emit`. T is the source element type, A the accumulator type. With
// renormalise, the used taps are scaled to sum to 1 when the image is smaller than the streak.
template <typename T, typename A, typename Emit>
void run_taps(const cv::Mat& src, const double* kernel, const std::vector<TapOffset>& offsets,
              bool renormalise, Emit emit) {
  const int rows = src.rows, cols = src.cols, ch = src.channels();
  const int taps = usable_taps(offsets, rows, cols);
  std::vector<A> weights(static_cast<std::size_t>(taps));
  double used = 0.0;
  for (int i = 0; i < taps; ++i) used += kernel[i];
  const bool scale = renormalise && taps < static_cast<int>(offsets.size()) && used > 0.0;
  for (int i = 0; i < taps; ++i) {
    weights[static_cast<std::size_t>(i)] = static_cast<A>(scale ? kernel[i] / used : kernel[i]);
  }
  int pad = 0;
  for (int i = 0; i < taps; ++i)
    pad = std::max(pad, std::abs(offsets[static_cast<std::size_t>(i)].dx));
  cv::Mat padded;
  cv::copyMakeBorder(src, padded, 0, 0, pad, pad, cv::BORDER_REPLICATE);
  const std::size_t n = static_cast<std::size_t>(cols) * static_cast<std::size_t>(ch);
  std::vector<A> acc(n);
  for (int y = 0; y < rows; ++y) {
    std::fill(acc.begin(), acc.end(), A(0));
    for (int i = 0; i < taps; ++i) {
      const auto& o = offsets[static_cast<std::size_t>(i)];
      const int sy = std::clamp(y - o.dy, 0, rows - 1);
      const T* row = padded.ptr<T>(sy) + static_cast<std::ptrdiff_t>(pad - o.dx) * ch;
      simd::axpy(acc.data(), row, weights[static_cast<std::size_t>(i)], n);
    }
    emit(y, acc.data(), n);
  }
}

template <typename A>
cv::Mat blur_u8(const cv::Mat& bgr, int severity, double angle_deg, bool renormalise) {
  const MotionBlurParams p = motion_blur_params(severity);
  const TabulatedKernel* k = find_tabulated_kernel(p.radius, p.sigma);
  const auto offsets = motion_offsets(angle_deg, k->width);
  cv::Mat out(bgr.size(), bgr.type());
  if constexpr (std::is_same_v<A, double>) {
    run_taps<std::uint8_t, A>(
        bgr, k->weights, offsets, renormalise, [&](int y, const A* acc, std::size_t n) {
          std::uint8_t* dst = out.ptr<std::uint8_t>(y);
          for (std::size_t j = 0; j < n; ++j)
            dst[j] = static_cast<std::uint8_t>(std::min(std::max(acc[j], 0.0), 255.0));
        });
  } else {
    // float32 sums sit within ~1e-4 of the exact double sum. Where a sum is that close to an
    // integer n the pixel is almost always in a flat region, whose exact result (n or n - 1,
    // decided by the last ulps of the double kernel) is tabulated here, so fast mode keeps flat
    // regions identical to numpy mode.
    const int taps = usable_taps(offsets, bgr.rows, bgr.cols);
    double used = 0.0;
    for (int i = 0; i < taps; ++i) used += k->weights[i];
    const bool scaled = renormalise && taps < k->width && used > 0.0;
    std::uint8_t flat[256];
    for (int v = 0; v < 256; ++v) {
      double sum = 0.0;
      for (int i = 0; i < taps; ++i) sum += (scaled ? k->weights[i] / used : k->weights[i]) * v;
      flat[v] = static_cast<std::uint8_t>(std::min(std::max(sum, 0.0), 255.0));
    }
    run_taps<std::uint8_t, A>(
        bgr, k->weights, offsets, renormalise, [&](int y, const A* acc, std::size_t n) {
          std::uint8_t* dst = out.ptr<std::uint8_t>(y);
          for (std::size_t j = 0; j < n; ++j) {
            const float v = std::min(std::max(acc[j], 0.0f), 255.0f);
            const float r = std::nearbyint(v);
            dst[j] =
                std::fabs(v - r) < 1e-3f ? flat[static_cast<int>(r)] : static_cast<std::uint8_t>(v);
          }
        });
  }
  return out;
}

}  // namespace

cv::Mat motion_blur_exact(const cv::Mat& bgr, int severity, double angle_deg) {
  return blur_u8<double>(bgr, severity, angle_deg, false);
}

namespace {

// Byte values as stored in a row ring: binary16 bit patterns (numpy mode: half the bytes per tap
// load, exact for bytes) or float32 (fast mode: the fused multiply-add reads its operand from
// memory, no conversion per tap).
inline std::uint16_t ring_value(std::uint8_t v, std::uint16_t*) { return simd::half_of_byte(v); }
inline float ring_value(std::uint8_t v, float*) { return static_cast<float>(v); }
inline void to_ring(const std::uint8_t* s, std::uint16_t* d, std::size_t n) {
  simd::u8_to_half(s, d, n);
}
inline void to_ring(const std::uint8_t* s, float* d, std::size_t n) { simd::u8_to_float(s, d, n); }
inline int byte_of(std::uint16_t h) { return static_cast<int>(simd::byte_of_half(h)); }
inline int byte_of(float f) { return static_cast<int>(f); }

// Source rows (columns [px0, px1)) converted once to T with `pad` pixels of edge-replicated margin
// on both sides, kept in a ring indexed by input row (slot r mod size): every output row reads at
// most `size` consecutive input rows, so each row is converted once per frame. Each converted row
// also gets its pixel-change bitmap (bit p set where element p differs from the same channel one
// pixel to the left), which lets the blur find stretches where every tap reads one colour without
// touching the rows.
template <typename T>
class RowRing {
 public:
  RowRing(const cv::Mat& src, int pad, int size, int px0, int px1)
      : src_(src), pad_(pad), size_(size), px0_(px0), px1_(px1) {
    const int ch = src.channels();
    stride_ = static_cast<std::size_t>(px1 - px0 + 2 * pad) * static_cast<std::size_t>(ch);
    // Bitmap words up to element stride + 128, everything from element `stride` on set: a scan for
    // the next change always stops there.
    words_ = (stride_ + 128) / 64 + 1;
    thread_local std::vector<T>
        storage;  // reused per thread: no fresh buffer (page faults) per frame
    thread_local std::vector<std::uint64_t> bit_storage;
    thread_local std::vector<std::uint32_t> skip_storage;
    storage.resize(stride_ * static_cast<std::size_t>(size) +
                   8);  // + 8: pixel loads of 8 bytes at the row end
    bit_storage.resize(words_ * static_cast<std::size_t>(size));
    skip_storage.resize(words_ * static_cast<std::size_t>(size));
    data_ = storage.data();
    bits_ = bit_storage.data();
    skip_ = skip_storage.data();
    tags_.assign(static_cast<std::size_t>(size), -1);
    slot_of_.resize(static_cast<std::size_t>(src.rows));
    for (int r = 0; r < src.rows; ++r) slot_of_[static_cast<std::size_t>(r)] = r % size;
  }
  // Row r (0 <= r < rows); element (x, c) of the image, px0 - pad <= x < px1 + pad, is at
  // [(x - px0 + pad) * ch + c].
  const T* row(int r) {
    const auto slot = static_cast<std::size_t>(slot_of_[static_cast<std::size_t>(r)]);
    T* d = data_ + slot * stride_;
    if (tags_[slot] != r) {
      tags_[slot] = r;
      const int ch = src_.channels(), cols = src_.cols;
      const std::uint8_t* s = src_.ptr<std::uint8_t>(r);
      const std::uint8_t* last = s + static_cast<std::ptrdiff_t>(cols - 1) * ch;
      T first_px[4], last_px[4];  // the replicated edge pixels (channels() <= 4)
      for (int c = 0; c < ch; ++c)
        first_px[c] = ring_value(s[c], d), last_px[c] = ring_value(last[c], d);
      int x = px0_ - pad_;
      T* o = d;
      for (; x < 0; ++x, o += ch) std::copy(first_px, first_px + ch, o);
      const int body_end = std::min(px1_ + pad_, cols);
      if (body_end > x) {
        to_ring(s + static_cast<std::ptrdiff_t>(x) * ch, o,
                static_cast<std::size_t>(body_end - x) * ch);
        o += static_cast<std::ptrdiff_t>(body_end - x) * ch;
        x = body_end;
      }
      for (; x < px1_ + pad_; ++x, o += ch) std::copy(last_px, last_px + ch, o);
      std::uint64_t* b = bits_ + slot * words_;
      std::fill(b + stride_ / 64, b + words_, ~std::uint64_t{0});
      simd::period_change_bits(d, stride_, static_cast<std::size_t>(ch), b);
      if (stride_ % 64 != 0) b[stride_ / 64] |= ~std::uint64_t{0} << (stride_ % 64);
      std::uint32_t* k = skip_ + slot * words_;
      auto next = static_cast<std::uint32_t>(words_ - 1);
      for (std::size_t w = words_; w-- > 0;) {
        if (b[w] != 0) next = static_cast<std::uint32_t>(w);
        k[w] = next;
      }
    }
    return d;
  }
  // Change bitmap of row r (valid after row(r)), in the same element indices, and per word the
  // first word at or after it with a set bit.
  const std::uint64_t* bits(int r) const {
    return bits_ + static_cast<std::size_t>(slot_of_[static_cast<std::size_t>(r)]) * words_;
  }
  const std::uint32_t* skips(int r) const {
    return skip_ + static_cast<std::size_t>(slot_of_[static_cast<std::size_t>(r)]) * words_;
  }

 private:
  const cv::Mat& src_;
  int pad_, size_, px0_, px1_;
  std::size_t stride_ = 0, words_ = 0;
  T* data_ = nullptr;
  std::uint64_t* bits_ = nullptr;
  std::uint32_t* skip_ = nullptr;
  std::vector<int> tags_;
  std::vector<int> slot_of_;  // r % size, precomputed (a division per tap and row is measurable)
};

// First set bit at or after position q, given skip[w] = first word at or after w with a set bit
// (the bitmap's last word is all ones).
inline std::size_t next_set_bit(const std::uint64_t* bits, const std::uint32_t* skip,
                                std::size_t q) {
  std::size_t w = q / 64;
  std::uint64_t m = bits[w] & (~std::uint64_t{0} << (q % 64));
  if (m == 0) {
    w = skip[w + 1];
    m = bits[w];
  }
  return 64 * w + static_cast<std::size_t>(__builtin_ctzll(m));
}

// The taps one blur applies: offsets and weights (float64 as the reference has them, float32 for
// the vector sums).
struct TapSet {
  std::vector<TapOffset> offsets;
  std::vector<double> weights64;
  std::vector<float> weights32;
  std::int32_t flat[256];  // the exact float64 result of a flat neighbourhood of value v (the exact
                           // path's order)
};

// The reference's taps for `severity` at `angle_deg` (the used ones: see usable_taps), renormalised
// to sum to 1 when `renormalise` and the image is smaller than the streak.
TapSet reference_taps(const cv::Mat& bgr, int severity, double angle_deg, bool renormalise) {
  const MotionBlurParams p = motion_blur_params(severity);
  const TabulatedKernel* k = find_tabulated_kernel(p.radius, p.sigma);
  TapSet t;
  t.offsets = motion_offsets(angle_deg, k->width);
  const int taps = usable_taps(t.offsets, bgr.rows, bgr.cols);
  t.offsets.resize(static_cast<std::size_t>(taps));
  double used = 0.0;
  for (int i = 0; i < taps; ++i) used += k->weights[i];
  const bool scale = renormalise && taps < k->width && used > 0.0;
  for (int i = 0; i < taps; ++i) {
    t.weights64.push_back(scale ? k->weights[i] / used : k->weights[i]);
    t.weights32.push_back(static_cast<float>(t.weights64.back()));
  }
  for (int v = 0; v < 256; ++v) {
    double sum = 0.0;
    for (const double w : t.weights64) sum += w * v;
    t.flat[v] = static_cast<std::int32_t>(std::min(std::max(sum, 0.0), 255.0));
  }
  return t;
}

// Drives a blur over whole output rows (measured faster than vertical strips of 64 pixels, also in
// fast mode: the long row streams prefetch well). Each row is cut into flat stretches, where every
// tap reads one and the same colour (every value is then the tabulated flat result: no sums, no
// reads of the taps' rows), and the rest, handed to sum_range(src, shifted, g0, g1, dst) in whole
// kBlock blocks: src[i] is tap i's row at element 0 and shifted[i] at element g0; it writes dst[g0,
// g1).
template <typename T, typename SumRange>
void banded_rows(const cv::Mat& bgr, const std::vector<TapOffset>& offsets,
                 const std::int32_t* flat, cv::Mat& out, SumRange sum_range) {
  const int rows = bgr.rows, cols = bgr.cols, ch = bgr.channels();
  const int taps = static_cast<int>(offsets.size());
  int pad = 0, dy_min = 0, dy_max = 0;
  for (const auto& o : offsets) {
    pad = std::max(pad, std::abs(o.dx));
    dy_min = std::min(dy_min, o.dy);
    dy_max = std::max(dy_max, o.dy);
  }
  constexpr std::size_t kBlock = 64;    // the kernels' block
  constexpr std::size_t kMinFlat = 64;  // shorter flat stretches are left to the kernel
  const auto uch = static_cast<std::size_t>(ch);
  constexpr std::size_t kPattern = 48;  // flat fills: a multiple of every channel count 1..4
  std::vector<std::size_t> tap_offset(
      static_cast<std::size_t>(taps));  // element j of tap i is ring element j + offset
  for (int i = 0; i < taps; ++i) {
    const auto t = static_cast<std::size_t>(i);
    tap_offset[t] = static_cast<std::size_t>(pad - offsets[t].dx) * uch;
  }
  std::vector<const T*> src(static_cast<std::size_t>(taps));
  std::vector<const std::uint64_t*> change(static_cast<std::size_t>(taps));
  std::vector<const std::uint32_t*> skip(static_cast<std::size_t>(taps));
  std::vector<const T*> shifted(static_cast<std::size_t>(taps));
  const std::size_t n = static_cast<std::size_t>(cols) * uch;
  RowRing<T> ring(bgr, pad, dy_max - dy_min + 1, 0, cols);
  for (int y = 0; y < rows; ++y) {
    for (int i = 0; i < taps; ++i) {
      const auto& o = offsets[static_cast<std::size_t>(i)];
      const int sy = std::clamp(y - o.dy, 0, rows - 1);
      src[static_cast<std::size_t>(i)] = ring.row(sy) + tap_offset[static_cast<std::size_t>(i)];
      change[static_cast<std::size_t>(i)] = ring.bits(sy);
      skip[static_cast<std::size_t>(i)] = ring.skips(sy);
    }
    std::uint8_t* dst = out.ptr<std::uint8_t>(y);
    // End of the flat stretch starting at element a (a if there is none of at least kMinFlat):
    // every tap's first pixel there equals tap 0's, and no tap's row changes pixel before the end.
    auto flat_end = [&](std::size_t a) {
      std::size_t end = n;
      const T* ref = src[0] + a;
      for (int i = taps - 1; i >= 0;
           --i) {  // the farthest tap first: it is the likeliest to differ
        const auto t = static_cast<std::size_t>(i);
        const T* first = src[t] + a;
        for (std::size_t c = 0; c < uch; ++c) {
          if (first[c] != ref[c]) return a;
        }
        const std::size_t off = tap_offset[t];
        end = std::min(end, next_set_bit(change[t], skip[t], a + off + uch) - off);
        if (end < a + kMinFlat) return a;
      }
      return end;
    };
    // Kernel sums over [g0, g1), widened to whole blocks (into neighbouring flat stretches, which
    // it recomputes to the same values) where the row is long enough.
    auto sum_blocks = [&](std::size_t g0, std::size_t g1) {
      const std::size_t len = (g1 - g0 + kBlock - 1) / kBlock * kBlock;
      if (len > n) {
        g0 = 0, g1 = n;
      } else {
        g0 = std::min(g0, n - len);
        g1 = g0 + len;
      }
      for (int i = 0; i < taps; ++i)
        shifted[static_cast<std::size_t>(i)] = src[static_cast<std::size_t>(i)] + g0;
      sum_range(src.data(), shifted.data(), g0, g1, dst);
    };
    std::size_t a = 0, pending = n;  // pending: start of the stretch not yet summed (n: none)
    while (a < n) {
      const std::size_t b = flat_end(a);
      if (b == a) {
        if (pending == n) pending = a;
        a = std::min(a + kBlock, n);
        continue;
      }
      if (pending != n) sum_blocks(pending, a);
      pending = n;
      // Fill [a, b) with the flat results of tap 0's pixel, 48 bytes (a whole number of pixels) at
      // a time.
      std::uint8_t pattern[kPattern];
      for (std::size_t c = 0; c < uch; ++c)
        pattern[c] = static_cast<std::uint8_t>(flat[byte_of(src[0][a + c])]);
      for (std::size_t c = uch; c < kPattern; ++c) pattern[c] = pattern[c - uch];
      std::uint8_t* d = dst + a;
      for (; d + kPattern <= dst + b; d += kPattern) std::memcpy(d, pattern, kPattern);
      std::memcpy(d, pattern, static_cast<std::size_t>(dst + b - d));
      a = b;
    }
    if (pending != n) sum_blocks(pending, n);
  }
}

// |float32 sum - real sum| <= (2 * taps + 2) * 256 * 2^-24 (weight, product and addition roundings
// on values
// <= 255 * sum(w); a fused multiply-add only removes the product rounding); the float64 reference
// is far closer.
float float32_band(int taps) { return static_cast<float>((2.0 * taps + 2.0) * 256.0 * 0x1p-24); }

cv::Mat blur_banded(const cv::Mat& bgr, int severity, double angle_deg) {
  // float32 sums (8 lanes per AVX2 FMA, register-blocked, over rows converted to half precision
  // once) decide every value whose truncation is unambiguous; the rest are recomputed with the
  // exact float64 sum, so the output equals the float64 path bit for bit.
  if (bgr.channels() > 4)
    return blur_u8<double>(bgr, severity, angle_deg, false);  // the ring assumes <= 4
  const TapSet t = reference_taps(bgr, severity, angle_deg, false);
  const int taps = static_cast<int>(t.offsets.size());
  const float band = float32_band(taps);
  const std::vector<double>& wd = t.weights64;
  cv::Mat out(bgr.size(), bgr.type());
  const std::size_t n =
      static_cast<std::size_t>(bgr.cols) * static_cast<std::size_t>(bgr.channels());
  std::vector<std::uint64_t> ambiguous(n / 64 + 1);
  // The exact float64 sums of `count` <= 4 values of row `dst` (the reference's order: products
  // rounded, then added), as independent chains: the add latency, not the arithmetic, bounds one
  // sum.
  auto exact_sums = [&](const std::uint16_t* const* rows_at, std::uint8_t* dst,
                        const std::size_t* lane, int count) {
    double sum[4] = {0.0, 0.0, 0.0, 0.0};
    for (int i = 0; i < taps; ++i) {
      const double w = wd[static_cast<std::size_t>(i)];
      for (int q = 0; q < 4; ++q)
        sum[q] += w * static_cast<double>(simd::byte_of_half(rows_at[i][lane[q]]));
    }
    for (int q = 0; q < count; ++q)
      dst[lane[q]] = static_cast<std::uint8_t>(std::min(std::max(sum[q], 0.0), 255.0));
  };
  // Ambiguous values the kernel left on [j_begin, j_begin + 64 * words) of row `dst` (bit k of word
  // w: value j_begin + 64 w + k).
  auto resolve = [&](const std::uint16_t* const* rows_at, std::uint8_t* dst, std::size_t j_begin,
                     std::size_t words) {
    std::size_t lane[4];
    int pending_sums = 0;
    for (std::size_t w = 0; w < words; ++w) {
      for (std::uint64_t m = ambiguous[w]; m != 0; m &= m - 1) {
        const std::size_t j = j_begin + 64 * w + static_cast<std::size_t>(__builtin_ctzll(m));
        // Flat neighbourhoods (all taps equal) land exactly on the band; their exact value is
        // tabulated.
        const std::uint16_t first = rows_at[0][j];
        int i = 1;
        while (i < taps && rows_at[i][j] == first) ++i;
        if (i == taps) {
          dst[j] = static_cast<std::uint8_t>(t.flat[static_cast<int>(simd::byte_of_half(first))]);
          continue;
        }
        // The half values are the bytes exactly, so this is the reference's sum of k_i * u8 value.
        lane[pending_sums++] = j;
        if (pending_sums == 4) {
          exact_sums(rows_at, dst, lane, 4);
          pending_sums = 0;
        }
      }
    }
    if (pending_sums > 0) {
      for (int q = pending_sums; q < 4; ++q)
        lane[q] = lane[0];  // padding lanes: summed, not stored
      exact_sums(rows_at, dst, lane, pending_sums);
    }
  };
  banded_rows<std::uint16_t>(
      bgr, t.offsets, t.flat, out,
      [&](const std::uint16_t* const* src, const std::uint16_t* const* shifted, std::size_t g0,
          std::size_t g1, std::uint8_t* dst) {
        if (simd::weighted_rows_truncate(shifted, t.weights32.data(), wd.data(), taps, band, t.flat,
                                         dst + g0, ambiguous.data(), g1 - g0) != 0) {
          resolve(src, dst, g0, (g1 - g0 + 63) / 64);
        }
      });
  return out;
}

// Fast mode: plain float32 sums over float32 rows, no float64 recompute (within 1 of numpy mode on
// a small fraction of values: see the header). Taps that land on the same pixel (up to ~30 % of
// them near 45 degrees) are merged into one tap with the summed weight.
cv::Mat blur_float32(const cv::Mat& bgr, int severity, double angle_deg) {
  if (bgr.channels() > 4)
    return blur_u8<double>(bgr, severity, angle_deg, true);  // the ring assumes <= 4
  const TapSet t = reference_taps(bgr, severity, angle_deg, true);
  std::vector<TapOffset> merged;
  std::vector<double> merged_weights;
  for (std::size_t i = 0; i < t.offsets.size(); ++i) {
    const TapOffset o = t.offsets[i];
    // Offsets move monotonically along the streak, so a repeated pixel is always the previous
    // tap's.
    if (!merged.empty() && merged.back().dy == o.dy && merged.back().dx == o.dx) {
      merged_weights.back() += t.weights64[i];
    } else {
      merged.push_back(o);
      merged_weights.push_back(t.weights64[i]);
    }
  }
  const std::vector<float> weights(merged_weights.begin(), merged_weights.end());
  const int taps = static_cast<int>(merged.size());
  // The float32 sums leave out the tail whose weights add up to at most kTail (sigma 3 and 5 have
  // ~1e-7 weights there: up to 6 of 31 taps fewer); the band grows by what they can add, so those
  // values are re-summed in float64.
  constexpr double kTail = 1.5e-6;
  int taps32 = taps;
  double tail = 0.0;
  while (taps32 > 1 && tail + merged_weights[static_cast<std::size_t>(taps32 - 1)] <= kTail) {
    tail += merged_weights[static_cast<std::size_t>(--taps32)];
  }
  const float band = float32_band(taps) + static_cast<float>(255.0 * tail);
  cv::Mat out(bgr.size(), bgr.type());
  banded_rows<float>(bgr, merged, t.flat, out,
                     [&](const float* const*, const float* const* shifted, std::size_t g0,
                         std::size_t g1, std::uint8_t* dst) {
                       simd::weighted_rows_truncate_fast(shifted, weights.data(), taps32,
                                                         merged_weights.data(), taps, band, t.flat,
                                                         dst + g0, g1 - g0);
                     });
  return out;
}

}  // namespace

cv::Mat motion_blur_fast(const cv::Mat& bgr, int severity, double angle_deg) {
  return blur_float32(bgr, severity, angle_deg);
}

cv::Mat motion_blur_numpy(const cv::Mat& bgr, int severity, double angle_deg) {
  return blur_banded(bgr, severity, angle_deg);
}

cv::Mat blur_layer(const cv::Mat& layer, int radius, int sigma, double angle_deg) {
  const TabulatedKernel* k = find_tabulated_kernel(radius, sigma);
  const auto offsets = motion_offsets(angle_deg, k->width);
  cv::Mat out(layer.size(), layer.type());
  if (layer.depth() == CV_64F) {
    run_taps<double, double>(layer, k->weights, offsets, false,
                             [&](int y, const double* acc, std::size_t n) {
                               std::copy(acc, acc + n, out.ptr<double>(y));
                             });
  } else {
    // Fast layer: register-blocked float32 sums, same tap order and rounding as the streaming
    // version.
    const int rows = layer.rows, cols = layer.cols;
    const int taps = usable_taps(offsets, rows, cols);
    double used = 0.0;
    for (int i = 0; i < taps; ++i) used += k->weights[i];
    const bool scale = taps < k->width && used > 0.0;
    std::vector<float> w(static_cast<std::size_t>(taps));
    int pad = 0;
    for (int i = 0; i < taps; ++i) {
      w[static_cast<std::size_t>(i)] =
          static_cast<float>(scale ? k->weights[i] / used : k->weights[i]);
      pad = std::max(pad, std::abs(offsets[static_cast<std::size_t>(i)].dx));
    }
    // Reused per thread: a fresh 6 MB buffer per frame costs more in page faults than the copy
    // itself.
    thread_local cv::Mat padded;
    cv::copyMakeBorder(layer, padded, 0, 0, pad, pad, cv::BORDER_REPLICATE);
    std::vector<const float*> src(static_cast<std::size_t>(taps));
    for (int y = 0; y < rows; ++y) {
      for (int i = 0; i < taps; ++i) {
        const auto& o = offsets[static_cast<std::size_t>(i)];
        src[static_cast<std::size_t>(i)] =
            padded.ptr<float>(std::clamp(y - o.dy, 0, rows - 1)) + (pad - o.dx);
      }
      simd::weighted_rows(out.ptr<float>(y), src.data(), w.data(), taps,
                          static_cast<std::size_t>(cols));
    }
  }
  return out;
}

}  // namespace faultline::corruption
