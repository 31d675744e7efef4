// Glass Blur: blur, local pixel copies in the reference's order, blur (fast mode: float32 blurs).
#include "corruption/glass_blur.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "common/simd.hpp"
#include "corruption/ndimage.hpp"

namespace faultline::corruption {

namespace {

// The pixel walk; draw() returns one offset in [-d, d).
template <typename Draw>
void shuffle_pixels(cv::Mat& img, const GlassParams& p, Draw&& draw) {
  const int d = p.delta;
  for (int it = 0; it < p.iterations; ++it) {
    for (int h = img.rows - d; h > d; --h) {
      for (int w = img.cols - d; w > d; --w) {
        const int dx = draw();
        const int dy = draw();
        const unsigned char* src = img.ptr<unsigned char>(h + dy) + 3 * (w + dx);
        unsigned char* dst = img.ptr<unsigned char>(h) + 3 * w;
        dst[0] = src[0], dst[1] = src[1], dst[2] = src[2];
      }
    }
  }
}

// fast mode's blur: numpy mode's separable kernel and edge replication in float32 on 0..255 values
// (8 lanes where numpy mode's float64 has 4; every sum within ~3e-4 of the float64 one). Where the
// float64 sum of a flat neighbourhood lands a hair below its integer, the reference truncates one
// level down, for some levels and not others: a float32 sum within 2e-3 of an integer k takes the
// reference's flat result for k (`flat`), every other one is truncated.
struct FastBlur {
  int r = 0;
  std::vector<float> w;                  // w[k]: weight at offset k, 0..r
  std::array<std::uint8_t, 256> flat{};  // the reference's output on a flat neighbourhood of v
};

FastBlur fast_blur(double sigma) {
  const std::vector<double> w = nd::gaussian_kernel(sigma, nd::gaussian_radius(sigma, 4.0));
  FastBlur b;
  b.r = static_cast<int>(w.size()) - 1;
  for (const double v : w) b.w.push_back(static_cast<float>(v));
  for (int v = 0; v < 256; ++v) {
    // nd::gaussian_blur_u8's operations on equal taps: axis 0, then axis 1, then the store.
    const double c = v / 255.0;
    double mid = c * w[0];
    for (int k = b.r; k >= 1; --k) mid += (c + c) * w[static_cast<std::size_t>(k)];
    double acc = mid * w[0];
    for (int k = b.r; k >= 1; --k) acc += (mid + mid) * w[static_cast<std::size_t>(k)];
    b.flat[static_cast<std::size_t>(v)] =
        static_cast<std::uint8_t>(std::min(std::max(acc, 0.0), 1.0) * 255.0);
  }
  return b;
}

// The tap sums with the radius known at compile time (3, 4 and 6 at severities 1-5): each output's
// sum stays in a register, where a loop per tap over the row stored and reloaded it at every tap.
// The order of the additions is the generic loops', so the sums are the same bit for bit.
template <int R>
[[gnu::always_inline]] inline void rows_fixed(float* out, const std::uint8_t* const* rows,
                                              const float* w, std::size_t n) {
  const std::uint8_t* p[2 * R + 1];
  float wk[R + 1];
  for (int k = 0; k <= 2 * R; ++k) p[k] = rows[k];
  for (int k = 0; k <= R; ++k) wk[k] = w[k];
#pragma GCC ivdep
  for (std::size_t i = 0; i < n; ++i) {
    float s = static_cast<float>(p[R][i]) * wk[0];
    for (int k = R; k >= 1; --k) s += static_cast<float>(p[R - k][i] + p[R + k][i]) * wk[k];
    out[i] = s;
  }
}

template <int R>
[[gnu::always_inline]] inline void cols_fixed(float* acc, const float* ext, const float* w,
                                              std::size_t n) {
  float wk[R + 1];
  for (int k = 0; k <= R; ++k) wk[k] = w[k];
#pragma GCC ivdep
  for (std::size_t i = 0; i < n; ++i) {
    float s = ext[i] * wk[0];
    for (int k = R; k >= 1; --k) s += (ext[i - 3 * k] + ext[i + 3 * k]) * wk[k];
    acc[i] = s;
  }
}

// Axis 0 straight from the 8-bit rows (each pair summed as integers, exact, so the same sums as
// from float rows, at a quarter of the memory traffic).
FAULTLINE_CLONES("avx2")
void blur_rows(float* out, const std::uint8_t* const* rows, const float* w, int r, std::size_t n) {
  switch (r) {
    case 3:
      return rows_fixed<3>(out, rows, w, n);
    case 4:
      return rows_fixed<4>(out, rows, w, n);
    case 6:
      return rows_fixed<6>(out, rows, w, n);
    default:
      break;
  }
  const std::uint8_t* mid = rows[r];
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(mid[i]) * w[0];
  for (int k = r; k >= 1; --k) {
    const std::uint8_t* a = rows[r - k];
    const std::uint8_t* b = rows[r + k];
    for (std::size_t i = 0; i < n; ++i) out[i] += static_cast<float>(a[i] + b[i]) * w[k];
  }
}

// Axis 1 over an interleaved row padded by r pixels each side (`ext` at the first real value),
// truncated; near[i] = 1 where the sum is within 2e-3 of the integer stored.
FAULTLINE_CLONES("avx2")
void blur_cols(std::uint8_t* dst, std::uint8_t* near, float* acc, const float* ext, const float* w,
               int r, std::size_t n) {
  switch (r) {
    case 3:
      cols_fixed<3>(acc, ext, w, n);
      break;
    case 4:
      cols_fixed<4>(acc, ext, w, n);
      break;
    case 6:
      cols_fixed<6>(acc, ext, w, n);
      break;
    default:
      for (std::size_t i = 0; i < n; ++i) acc[i] = ext[i] * w[0];
      for (int k = r; k >= 1; --k) {
        const float* a = ext - 3 * k;
        const float* b = ext + 3 * k;
        for (std::size_t i = 0; i < n; ++i) acc[i] += (a[i] + b[i]) * w[k];
      }
  }
  // Separate loops with int32 conversions, so that each vectorises.
  // (Sums are never below -2e-3, so the conversion truncates like floor; clamping the integer
  // keeps the loop free of branches.)
  for (std::size_t i = 0; i < n; ++i) {
    std::int32_t k = static_cast<std::int32_t>(acc[i] + 2e-3f);
    acc[i] -= static_cast<float>(k);
    k = k < 0 ? 0 : k;
    dst[i] = static_cast<std::uint8_t>(k > 255 ? 255 : k);
  }
  for (std::size_t i = 0; i < n; ++i) {
    near[i] = static_cast<std::uint8_t>(static_cast<std::int32_t>(acc[i] < 2e-3f));
  }
}

// o[x] = flat[o[x]] where near[x]: 32 flags at a time tested as four words first (few are set, and
// a byte-wise branch mispredicted often enough to cost a tenth of the corruption).
void fix_flat(std::uint8_t* o, const std::uint8_t* near, const std::array<std::uint8_t, 256>& flat,
              std::size_t n) {
  std::size_t x0 = 0;
  for (; x0 + 32 <= n; x0 += 32) {
    std::uint64_t w[4];
    std::memcpy(w, near + x0, sizeof w);
    if ((w[0] | w[1] | w[2] | w[3]) == 0) continue;
    for (std::size_t x = x0; x < x0 + 32; ++x) {
      if (near[x]) o[x] = flat[o[x]];
    }
  }
  for (std::size_t x = x0; x < n; ++x) {
    if (near[x]) o[x] = flat[o[x]];
  }
}

void blur_fast(const cv::Mat& bgr, const FastBlur& b, cv::Mat& out) {
  const int r = b.r, rows = bgr.rows;
  const auto n = static_cast<std::size_t>(bgr.cols) * 3;
  std::vector<float> line(n + 6 * static_cast<std::size_t>(r)), acc(n);
  std::vector<std::uint8_t> near(n);
  std::vector<const std::uint8_t*> taps(static_cast<std::size_t>(2 * r + 1));
  float* mid = line.data() + 3 * r;
  out.create(bgr.size(), CV_8UC3);
  for (int i = 0; i < rows; ++i) {
    for (int k = -r; k <= r; ++k) {
      taps[static_cast<std::size_t>(k + r)] = bgr.ptr<std::uint8_t>(std::clamp(i + k, 0, rows - 1));
    }
    blur_rows(mid, taps.data(), b.w.data(), r, n);
    for (int k = 1; k <= r; ++k) {
      for (std::size_t c = 0; c < 3; ++c) {
        mid[static_cast<std::ptrdiff_t>(c) - 3 * k] = mid[c];
        mid[n - 3 + 3 * static_cast<std::size_t>(k) + c] = mid[n - 3 + c];
      }
    }
    std::uint8_t* o = out.ptr<std::uint8_t>(i);
    blur_cols(o, near.data(), acc.data(), mid, b.w.data(), r, n);
    fix_flat(o, near.data(), b.flat, n);
  }
}

// out[i] = (chunk[i] * span) >> 16 - delta: OffsetStream's map, eight or sixteen at a time.
FAULTLINE_CLONES("avx2")
void map_chunks(std::int8_t* out, const std::uint16_t* chunk, std::size_t n, std::uint32_t span,
                int delta) {
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = static_cast<std::int8_t>(static_cast<int>((chunk[i] * span) >> 16) - delta);
  }
}

// fast mode's offsets: four to a 64-bit draw, 16 bits each, scaled to [-d, d) by multiply and
// shift (uniform for d = 1, 2, 4; for d = 3 four of the six values are 1 / 10922 more likely than
// the other two, far below anything the output shows). Drawn a row at a time, in the walk's order.
class OffsetStream {
 public:
  OffsetStream(rng::FastRng& rng, int delta)
      : rng_(rng), delta_(delta), span_(static_cast<std::uint64_t>(2 * delta)) {}
  void fill(std::int8_t* out, std::size_t n) {
    std::size_t i = 0;
    for (; i < n && left_ > 0; ++i) out[i] = take();
    // The whole words' chunks first (the draws are serial), then mapped in one vector loop.
    const std::size_t words = (n - i) / 4;
    chunks_.resize(4 * words);
    for (std::size_t j = 0; j < words; ++j) {
      const std::uint64_t w = rng_.next_u64();
      for (std::size_t k = 0; k < 4; ++k)
        chunks_[4 * j + k] = static_cast<std::uint16_t>(w >> (16 * k));
    }
    map_chunks(out + i, chunks_.data(), chunks_.size(), static_cast<std::uint32_t>(span_), delta_);
    i += chunks_.size();
    for (; i < n; ++i) out[i] = take();
  }

 private:
  std::int8_t map(std::uint64_t chunk) const {
    return static_cast<std::int8_t>(static_cast<int>(((chunk & 0xFFFFu) * span_) >> 16) - delta_);
  }
  std::int8_t take() {
    if (left_ == 0) word_ = rng_.next_u64(), left_ = 4;
    const std::int8_t v = map(word_);
    word_ >>= 16, --left_;
    return v;
  }
  rng::FastRng& rng_;
  int delta_;
  std::uint64_t span_;
  std::uint64_t word_ = 0;
  int left_ = 0;
  std::vector<std::uint16_t> chunks_;
};

// shuffle_pixels with OffsetStream's draws (dx, then dy, per pixel), a row's offsets drawn and
// turned into byte offsets before its serial copy loop (a copy may read a pixel the walk wrote).
void walk_fast(cv::Mat& img, const GlassParams& p, rng::FastRng& rng) {
  const int d = p.delta;
  if (img.cols - 2 * d <= 0) return;
  const auto count = static_cast<std::size_t>(img.cols - 2 * d);
  std::vector<std::int8_t> draws(2 * count);
  std::vector<std::ptrdiff_t> offset(count);
  const auto step = static_cast<std::ptrdiff_t>(img.step[0]);
  OffsetStream stream(rng, d);
  for (int it = 0; it < p.iterations; ++it) {
    for (int h = img.rows - d; h > d; --h) {
      stream.fill(draws.data(), draws.size());
      for (std::size_t k = 0; k < count; ++k)
        offset[k] = draws[2 * k + 1] * step + 3 * draws[2 * k];
      unsigned char* px = img.ptr<unsigned char>(h) + 3 * (img.cols - d);  // w = cols - d first
      for (std::size_t k = 0; k < count; ++k, px -= 3) {
        // Two loads and two stores where three of each did it (src is px or a whole pixel away).
        const unsigned char* src = px + offset[k];
        std::uint16_t first;
        std::memcpy(&first, src, 2);
        const unsigned char last = src[2];
        std::memcpy(px, &first, 2);
        px[2] = last;
      }
    }
  }
}

}  // namespace

GlassParams glass_params(int severity) {
  static constexpr GlassParams kParams[] = {
      {0.7, 1, 2}, {0.9, 2, 1}, {1, 2, 3}, {1.1, 3, 2}, {1.5, 4, 2}};
  return kParams[severity - 1];
}

cv::Mat glass_blur_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const GlassParams p = glass_params(severity);
  // np.uint8(gaussian(...) * 255): the blurred values are within [0, 1], so the clip in
  // gaussian_blur_u8 changes nothing.
  cv::Mat img = nd::gaussian_blur_u8(bgr, p.sigma);
  shuffle_pixels(img, p, [&] { return static_cast<int>(rng.randint(-p.delta, p.delta)); });
  return nd::gaussian_blur_u8(img, p.sigma);
}

cv::Mat glass_blur_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const GlassParams p = glass_params(severity);
  // The float32 blur at every severity: below sigma 1 (severities 1 and 2: 7 and 9 taps) it misses
  // numpy mode's float64 blur on ~5 % of the values of a linear ramp (whose float64 sums land on or
  // a hair below integers without being flat), by one level; from sigma 1 on ~0.1 %.
  // (gaussian_blur's dithered 8-bit blur, a third of the cost, was tried: it keeps flat areas at
  // their level where the reference's float64 sums truncate some levels one down, and the
  // histogram moves ten times as far from numpy mode's as another seed's does.)
  const FastBlur blur = fast_blur(p.sigma);
  // The first blur's image is scratch, one per thread (the same size frame after frame: no fresh
  // 4 MB of pages per frame).
  thread_local cv::Mat img;
  blur_fast(bgr, blur, img);
  walk_fast(img, p, rng);
  cv::Mat out;
  blur_fast(img, blur, out);
  return out;
}

}  // namespace faultline::corruption
