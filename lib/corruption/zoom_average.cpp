// zoom_blur's cascade step: columns interpolated once per source row (kept for the next output
// row, since a zoom above 1 moves at most one source row per output row), rows and the mean fused.
#include "corruption/zoom_average.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "common/simd.hpp"

namespace faultline::corruption {

namespace {

constexpr int kColumnOne = 64;     // column weights in Q6: 255 * 64 fits a signed 16-bit lane
constexpr int kRowOne = 1 << 15;   // row weights in Q15, as _mm256_mulhrs_epi16 takes them
constexpr std::size_t kChunk = 8;  // output values per 16-byte shuffle window

// One output coordinate's two samples and the weight of the second, in units of `one`.
struct Tap {
  int first = 0, second = 0, weight = 0;
};

// scipy.ndimage.zoom's order-1 taps along one axis, for `count` outputs from index `trim` on.
std::vector<Tap> zoom_taps(int n_in, int n_out, int trim, int count, int one) {
  const double ratio =
      n_out > 1 ? static_cast<double>(n_in - 1) / static_cast<double>(n_out - 1) : 0.0;
  std::vector<Tap> taps(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    const double c = static_cast<double>(i + trim) * ratio;
    Tap& t = taps[static_cast<std::size_t>(i)];
    t.first = std::min(static_cast<int>(std::floor(c)), n_in - 1);
    t.weight = static_cast<int>(std::lround((c - t.first) * one));
    if (t.weight >= one) {  // rounds onto the next sample: take it alone (Q15 has no 1.0)
      t.first = std::min(t.first + 1, n_in - 1);
      t.weight = 0;
    }
    t.second = std::min(t.first + 1, n_in - 1);
  }
  return taps;
}

// The column pass for one crop: per output value (pixel x channel) the byte offsets of its two
// samples in a source row and the Q6 weight of the second; for the vector path, per 8 values a
// 16-byte window's offset, the shuffle that pairs each value's samples in it and the weight pairs.
struct ColumnPlan {
  std::vector<int> first, second, weight;
  std::vector<int> window;
  std::vector<std::int8_t> shuffle, pair_weight;
  std::size_t vector_values = 0;  // values [0, vector_values) take the vector path
};

bool plan_chunk(ColumnPlan& p, std::size_t k, int window, std::size_t row_bytes) {
  if (static_cast<std::size_t>(window) + 16 > row_bytes) return false;
  p.window[k] = window;
  for (std::size_t j = 0; j < kChunk; ++j) {
    const std::size_t i = kChunk * k + j;
    const int a = p.first[i] - window, b = p.second[i] - window;
    if (a < 0 || b < 0 || a > 15 || b > 15) return false;
    p.shuffle[2 * i] = static_cast<std::int8_t>(a);
    p.shuffle[2 * i + 1] = static_cast<std::int8_t>(b);
    p.pair_weight[2 * i] = static_cast<std::int8_t>(kColumnOne - p.weight[i]);
    p.pair_weight[2 * i + 1] = static_cast<std::int8_t>(p.weight[i]);
  }
  return true;
}

ColumnPlan column_plan(int cols, const cv::Rect& crop, int scaled_cols) {
  const auto taps = zoom_taps(crop.width, scaled_cols, (scaled_cols - cols) / 2, cols, kColumnOne);
  const auto n = static_cast<std::size_t>(cols) * 3;
  ColumnPlan p;
  p.first.resize(n);
  p.second.resize(n);
  p.weight.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Tap& t = taps[i / 3];
    const auto c = static_cast<int>(i % 3);
    p.first[i] = (crop.x + t.first) * 3 + c;
    p.second[i] = (crop.x + t.second) * 3 + c;
    p.weight[i] = t.weight;
  }
  // Vector chunks go in pairs (one per 128-bit lane), from the left while their windows fit: a
  // zoom of at least 1 moves at most one source pixel per output pixel, so 8 values span at most
  // 4 source pixels plus the next one (15 bytes); only the right edge's windows run off the row.
  const std::size_t chunks = n / kChunk;
  p.window.resize(chunks);
  p.shuffle.resize(2 * kChunk * chunks);
  p.pair_weight.resize(2 * kChunk * chunks);
  std::size_t k = 0;
  for (; k + 2 <= chunks; k += 2) {
    const int w0 = (crop.x + taps[kChunk * k / 3].first) * 3;
    const int w1 = (crop.x + taps[kChunk * (k + 1) / 3].first) * 3;
    if (!plan_chunk(p, k, w0, n) || !plan_chunk(p, k + 1, w1, n)) break;
  }
  p.vector_values = kChunk * k;
  return p;
}

void column_pass(std::int16_t* h, const std::uint8_t* row, const ColumnPlan& p, std::size_t from) {
  for (std::size_t i = from; i < p.first.size(); ++i) {
    const int w = p.weight[static_cast<std::size_t>(i)];
    h[i] = static_cast<std::int16_t>(row[p.first[i]] * (kColumnOne - w) + row[p.second[i]] * w);
  }
}

// layer = h0 + round((h1 - h0) w / 2^15) (mulhrs), out = (64 a + layer + bias) >> 7: at most
// 64 * 255 * 2 + 127 = 32 767, so every step fits a signed 16-bit lane.
void row_pass(std::uint8_t* out, const std::uint8_t* a, const std::int16_t* h0,
              const std::int16_t* h1, int w, int bias, std::size_t from, std::size_t n) {
  for (std::size_t i = from; i < n; ++i) {
    const int layer = h0[i] + (((h1[i] - h0[i]) * w + (1 << 14)) >> 15);
    out[i] = static_cast<std::uint8_t>((kColumnOne * a[i] + layer + bias) >> 7);
  }
}

#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET("avx2")
void column_pass_avx2(std::int16_t* h, const std::uint8_t* row, const ColumnPlan& p) {
  for (std::size_t k = 0; kChunk * k < p.vector_values; k += 2) {
    const __m256i src = _mm256_inserti128_si256(
        _mm256_castsi128_si256(
            _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + p.window[k]))),
        _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + p.window[k + 1])), 1);
    const __m256i pairs = _mm256_shuffle_epi8(
        src, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(&p.shuffle[2 * kChunk * k])));
    const __m256i w =
        _mm256_loadu_si256(reinterpret_cast<const __m256i*>(&p.pair_weight[2 * kChunk * k]));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(h + kChunk * k), _mm256_maddubs_epi16(pairs, w));
  }
}

FAULTLINE_TARGET("avx2")
std::size_t row_pass_avx2(std::uint8_t* out, const std::uint8_t* a, const std::int16_t* h0,
                          const std::int16_t* h1, int w, int bias, std::size_t n) {
  const __m256i wv = _mm256_set1_epi16(static_cast<std::int16_t>(w));
  const __m256i bv = _mm256_set1_epi16(static_cast<std::int16_t>(bias));
  auto mean16 = [&](std::size_t at) FAULTLINE_TARGET_INLINE("avx2") {
    const __m256i x0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(h0 + at));
    const __m256i x1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(h1 + at));
    const __m256i layer = _mm256_add_epi16(x0, _mm256_mulhrs_epi16(_mm256_sub_epi16(x1, x0), wv));
    const __m256i av =
        _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + at)));
    const __m256i sum = _mm256_add_epi16(_mm256_add_epi16(_mm256_slli_epi16(av, 6), layer), bv);
    return _mm256_srli_epi16(sum, 7);
  };
  std::size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    const __m256i bytes = _mm256_packus_epi16(mean16(i), mean16(i + 16));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), _mm256_permute4x64_epi64(bytes, 0xD8));
  }
  return i;
}
#endif

// The column pass's rows for the last two source rows asked for.
class RowCache {
 public:
  explicit RowCache(std::size_t values)
      : slots_{std::vector<std::int16_t>(values), std::vector<std::int16_t>(values)} {}

  const std::int16_t* get(const cv::Mat& in, int r, int keep, const ColumnPlan& p, bool simd) {
    for (int s = 0; s < 2; ++s)
      if (id_[s] == r) return slots_[s].data();
    const int s = id_[0] == keep ? 1 : 0;
    std::int16_t* h = slots_[s].data();
    const std::uint8_t* src = in.ptr<std::uint8_t>(r);
    std::size_t from = 0;
#if FAULTLINE_X86_SIMD
    if (simd) {
      column_pass_avx2(h, src, p);
      from = p.vector_values;
    }
#else
    (void)simd;
#endif
    column_pass(h, src, p, from);
    id_[s] = r;
    return h;
  }

 private:
  std::vector<std::int16_t> slots_[2];
  int id_[2] = {-1, -1};
};

}  // namespace

void zoom_average(const cv::Mat& in, const cv::Rect& crop, const cv::Size& scaled, int bias,
                  cv::Mat& out) {
  if (in.type() != CV_8UC3 || in.empty())
    throw std::invalid_argument("zoom_average: the frame must be a non-empty CV_8UC3 image");
  if (crop.empty() || (crop & cv::Rect(0, 0, in.cols, in.rows)) != crop)
    throw std::invalid_argument("zoom_average: the crop must be a non-empty part of the frame");
  if (scaled.width < in.cols || scaled.height < in.rows)
    throw std::invalid_argument("zoom_average: the scaled crop must cover the frame");
  if (bias < 0 || bias > 127) throw std::invalid_argument("zoom_average: bias must be in [0, 127]");
  if (out.data == in.data) throw std::invalid_argument("zoom_average: out must not be the input");
  out.create(in.size(), CV_8UC3);
  const ColumnPlan plan = column_plan(in.cols, crop, scaled.width);
  const auto rows =
      zoom_taps(crop.height, scaled.height, (scaled.height - in.rows) / 2, in.rows, kRowOne);
  const auto n = static_cast<std::size_t>(in.cols) * 3;
  const bool simd = common::cpu_has_avx2();
  RowCache cache(n);
  for (int y = 0; y < in.rows; ++y) {
    const Tap& t = rows[static_cast<std::size_t>(y)];
    const int r0 = crop.y + t.first, r1 = crop.y + t.second;
    const std::int16_t* h0 = cache.get(in, r0, r1, plan, simd);
    const std::int16_t* h1 = cache.get(in, r1, r0, plan, simd);
    const std::uint8_t* a = in.ptr<std::uint8_t>(y);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    std::size_t from = 0;
#if FAULTLINE_X86_SIMD
    if (simd) from = row_pass_avx2(o, a, h0, h1, t.weight, bias, n);
#endif
    row_pass(o, a, h0, h1, t.weight, bias, from, n);
  }
}

}  // namespace faultline::corruption
