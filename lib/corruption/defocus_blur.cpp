// Defocus Blur: the reference's disk kernel and its per-channel float64 correlation.
#include "corruption/defocus_blur.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/simd.hpp"

namespace faultline::corruption {

DefocusParams defocus_params(int severity) {
  static constexpr DefocusParams kParams[] = {{3, 0.1}, {4, 0.5}, {6, 0.5}, {8, 0.5}, {10, 0.5}};
  return kParams[severity - 1];
}

cv::Mat defocus_kernel(int severity) {
  const DefocusParams p = defocus_params(severity);
  const int half = p.radius <= 8 ? 8 : p.radius;
  const int ksize = p.radius <= 8 ? 3 : 5;
  const int n = 2 * half + 1;
  cv::Mat disk(n, n, CV_32F);
  int count = 0;
  for (int y = -half; y <= half; ++y) {
    for (int x = -half; x <= half; ++x) {
      const bool inside = x * x + y * y <= p.radius * p.radius;
      disk.at<float>(y + half, x + half) = inside ? 1.f : 0.f;
      count += inside;
    }
  }
  const float sum = static_cast<float>(count);  // the float32 sum of ones is exact in any order
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) disk.at<float>(y, x) /= sum;  // a true division, as NumPy's /=
  }
  cv::Mat kernel;
  cv::GaussianBlur(disk, kernel, cv::Size(ksize, ksize), p.alias_blur);
  return kernel;
}

namespace {

// clip(v, 0, 1) * 255, truncated: the reference's last step (float64).
void store_truncated(const cv::Mat& channel, cv::Mat& out, int c) {
  for (int y = 0; y < channel.rows; ++y) {
    const double* s = channel.ptr<double>(y);
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < channel.cols; ++x) {
      o[3 * x + c] = static_cast<unsigned char>(std::min(std::max(s[x], 0.0), 1.0) * 255.0);
    }
  }
}

}  // namespace

cv::Mat defocus_blur_exact(const cv::Mat& bgr, int severity) {
  const cv::Mat kernel = defocus_kernel(severity);
  cv::Mat channels[3];
  for (auto& ch : channels) ch.create(bgr.size(), CV_64F);
  for (int y = 0; y < bgr.rows; ++y) {
    const unsigned char* s = bgr.ptr<unsigned char>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      for (int c = 0; c < 3; ++c)
        channels[c].at<double>(y, x) = s[3 * x + c] / 255.0;  // u8 / 255. in float64
    }
  }
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int c = 0; c < 3; ++c) {
    cv::Mat filtered;
    cv::filter2D(channels[c], filtered, -1, kernel);
    store_truncated(filtered, out, c);
  }
  return out;
}

namespace {

// fast mode's decomposition of the kernel: the binary disk (its sums exact in integers) smoothed by
// the separable anti-aliasing Gaussian, plus the few taps where the reference's kernel differs from
// that (its 17 x 17 / 21 x 21 grid cuts the smoothed rim off and reflect-101 folds it back in at
// severities 4 and 5).
struct DiskPlan {
  int radius = 0, half = 0, smooth = 0;  // disk radius, kernel half-size, Gaussian half-size
  std::vector<int> run;                  // run[dx + radius]: the disk covers |dy| <= run at dx
  std::vector<float> g;                  // anti-aliasing weights, 2 * smooth + 1
  float inv_count = 0;
  struct Tap {
    int dy, dx;
    float w;
  };
  std::vector<Tap> residual;
  float bias = 0;
};

DiskPlan disk_plan(int severity) {
  const DefocusParams p = defocus_params(severity);
  const cv::Mat kernel = defocus_kernel(severity);
  DiskPlan plan;
  plan.radius = p.radius;
  plan.half = kernel.rows / 2;
  plan.smooth = p.radius <= 8 ? 1 : 2;  // defocus_kernel's 3 x 3 or 5 x 5
  const cv::Mat g = cv::getGaussianKernel(2 * plan.smooth + 1, p.alias_blur, CV_64F);
  int count = 0;
  for (int dx = -p.radius; dx <= p.radius; ++dx) {
    int h = 0;
    while ((h + 1) * (h + 1) + dx * dx <= p.radius * p.radius) ++h;
    plan.run.push_back(h);
    count += 2 * h + 1;
  }
  for (int i = 0; i < g.rows; ++i) plan.g.push_back(static_cast<float>(g.at<double>(i)));
  plan.inv_count = 1.f / static_cast<float>(count);
  // The smoothed disk on a grid wide enough to hold all of it, minus the reference's kernel.
  const int ext = plan.half + plan.smooth, n = 2 * ext + 1;
  cv::Mat diff = cv::Mat::zeros(n, n, CV_64F);
  for (int dx = -p.radius; dx <= p.radius; ++dx) {
    const int h = plan.run[static_cast<std::size_t>(dx + p.radius)];
    for (int dy = -h; dy <= h; ++dy) {
      for (int sy = -plan.smooth; sy <= plan.smooth; ++sy) {
        for (int sx = -plan.smooth; sx <= plan.smooth; ++sx) {
          diff.at<double>(ext + dy + sy, ext + dx + sx) -=
              g.at<double>(sy + plan.smooth) * g.at<double>(sx + plan.smooth) / count;
        }
      }
    }
  }
  for (int y = 0; y < kernel.rows; ++y) {
    for (int x = 0; x < kernel.cols; ++x) {
      diff.at<double>(y + plan.smooth, x + plan.smooth) += kernel.at<float>(y, x);
    }
  }
  // What is left lies along the four sides of the grid (severities 4 and 5: rows or columns of
  // ~5e-4 and the cut-off rim beyond them); per side its mass goes to three taps on the side's
  // centre line, spread to the same second moment along the side (at most ~1e-3 of the kernel
  // moves by a pixel or two). Below 1e-6 an entry is float rounding of the kernel and is dropped.
  struct Side {
    double mass = 0, across = 0, along2 = 0;
  } sides[4];  // top, bottom, left, right
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const double w = diff.at<double>(y, x);
      if (std::fabs(w) <= 1e-6) continue;
      const int dy = y - ext, dx = x - ext;
      const bool rows = std::abs(dy) >= std::abs(dx);
      Side& side = sides[rows ? (dy < 0 ? 0 : 1) : (dx < 0 ? 2 : 3)];
      side.mass += w;
      side.across += w * (rows ? dy : dx);
      side.along2 += w * (rows ? dx * dx : dy * dy);
    }
  }
  for (int k = 0; k < 4; ++k) {
    const Side& side = sides[k];
    if (std::fabs(side.mass) <= 1e-6) continue;
    const int across = static_cast<int>(std::lround(side.across / side.mass));
    const int spread =
        static_cast<int>(std::lround(std::sqrt(std::max(side.along2 / side.mass, 0.0) * 1.5)));
    // Always three taps of a third each (the same tap thrice at spread 0): the rows sum a side's
    // three pixels in integers and weigh them once.
    for (const int along : {-spread, 0, spread}) {
      const auto w = static_cast<float>(side.mass / 3.0);
      plan.residual.push_back(k < 2 ? DiskPlan::Tap{across, along, w}
                                    : DiskPlan::Tap{along, across, w});
    }
  }
  // Kernels summing a hair below 1 (severities 1-3) put the reference's flat areas just below their
  // integer, which truncates one level down; float32 cannot resolve that deficit, so it is applied
  // as a small bias.
  plan.bias = cv::sum(kernel)[0] < 1.0 ? -1e-3f : 0.f;
  return plan;
}

FAULTLINE_CLONES("avx2")
void add_u8(std::int32_t* acc, const std::uint8_t* row, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) acc[i] += row[i];
}

// The disk's move down one row: per value, the pixels entering below the disk's 2 r + 1 columns
// minus those leaving above them. Up to 2 r + 1 <= 127 pixels each way, so the change fits 16
// bits: it is summed 16 values to a vector, then added to the 32-bit sums. Integers: the portable
// loop gives the same sums.
void disk_step_portable(std::int32_t* disk, const std::uint8_t* const* enter,
                        const std::uint8_t* const* leave, int columns, std::size_t from,
                        std::size_t n) {
  for (std::size_t i = from; i < n; ++i) {
    std::int32_t change = 0;
    for (int c = 0; c < columns; ++c) change += enter[c][i] - leave[c][i];
    disk[i] += change;
  }
}

#if FAULTLINE_X86_SIMD
// 32 values a step: the entering and leaving bytes interleaved and multiply-added with +1 / -1
// (in - out per value in 16 bits). Within each 128-bit lane, `low` holds values 0-7 (16-23 in the
// upper lane) and `high` 8-15 (24-31).
FAULTLINE_TARGET("avx2")
std::size_t disk_step_avx2(std::int32_t* disk, const std::uint8_t* const* enter,
                           const std::uint8_t* const* leave, int columns, std::size_t n) {
  const __m256i in_out = _mm256_set1_epi16(static_cast<std::int16_t>(0xFF01));  // bytes +1, -1
  std::size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    __m256i low = _mm256_setzero_si256(), high = _mm256_setzero_si256();
    for (int c = 0; c < columns; ++c) {
      const __m256i in = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(enter[c] + i));
      const __m256i out = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(leave[c] + i));
      low = _mm256_add_epi16(low, _mm256_maddubs_epi16(_mm256_unpacklo_epi8(in, out), in_out));
      high = _mm256_add_epi16(high, _mm256_maddubs_epi16(_mm256_unpackhi_epi8(in, out), in_out));
    }
    auto add = [&](std::size_t at, __m128i change) FAULTLINE_TARGET_INLINE("avx2") {
      auto* d = reinterpret_cast<__m256i*>(disk + i + at);
      _mm256_storeu_si256(d,
                          _mm256_add_epi32(_mm256_loadu_si256(d), _mm256_cvtepi16_epi32(change)));
    };
    add(0, _mm256_castsi256_si128(low));
    add(8, _mm256_castsi256_si128(high));
    add(16, _mm256_extracti128_si256(low, 1));
    add(24, _mm256_extracti128_si256(high, 1));
  }
  return i;
}
#endif

void disk_step(std::int32_t* disk, const std::uint8_t* const* enter,
               const std::uint8_t* const* leave, int columns, std::size_t n) {
  std::size_t from = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) from = disk_step_avx2(disk, enter, leave, columns, n);
#endif
  disk_step_portable(disk, enter, leave, columns, from, n);
}

// The two row passes after the disk sums, one value at a time in a fixed order (no fused
// multiply-adds), so the AVX2 bodies, which keep the sums in registers across the taps, give the
// same floats as the portable loops.
//   h[i] = sum_t w[t] * disk[i + 3 t] (the anti-aliasing Gaussian across, over the disk's count);
//   out[i] = trunc(sum_t g[t] rows[t][i] + sum_k residual_w[k] (the sum of residual[3 k .. 3 k + 2]
//            at i) + bias), clamped.
struct FinishTaps {
  const float* const* rows;
  const float* g;
  int taps;
  const std::uint8_t* const* residual;
  const float* residual_w;
  int residuals;  // sides: three pixels each
  float bias;
};

void smooth_portable(float* h, const std::int32_t* disk, const float* w, int taps, std::size_t from,
                     std::size_t n) {
  for (std::size_t i = from; i < n; ++i) {
    float v = w[0] * static_cast<float>(disk[i]);
    for (int t = 1; t < taps; ++t) v += w[t] * static_cast<float>(disk[i + 3 * t]);
    h[i] = v;
  }
}

void finish_portable(std::uint8_t* out, const FinishTaps& f, std::size_t from, std::size_t n) {
  for (std::size_t i = from; i < n; ++i) {
    float v = f.g[0] * f.rows[0][i];
    for (int t = 1; t < f.taps; ++t) v += f.g[t] * f.rows[t][i];
    for (int k = 0; k < f.residuals; ++k) {
      const std::uint8_t* const* p = f.residual + 3 * k;
      v += f.residual_w[k] * static_cast<float>(p[0][i] + p[1][i] + p[2][i]);
    }
    // Clamped after the int32 conversion (truncation toward zero).
    const std::int32_t q = static_cast<std::int32_t>(v + f.bias);
    out[i] = static_cast<std::uint8_t>(std::min(std::max(q, 0), 255));
  }
}

#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET("avx2")
std::size_t smooth_avx2(float* h, const std::int32_t* disk, const float* w, int taps,
                        std::size_t n) {
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    auto tap = [&](int t) FAULTLINE_TARGET_INLINE("avx2") {
      const __m256i d = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(disk + i + 3 * t));
      return _mm256_mul_ps(_mm256_set1_ps(w[t]), _mm256_cvtepi32_ps(d));
    };
    __m256 v = tap(0);
    for (int t = 1; t < taps; ++t) v = _mm256_add_ps(v, tap(t));
    _mm256_storeu_ps(h + i, v);
  }
  return i;
}

FAULTLINE_TARGET("avx2")
std::size_t finish_avx2(std::uint8_t* out, const FinishTaps& f, std::size_t n) {
  // The Gaussian's rows for 8 values, then each rim side's three pixels, summed for 16 values at
  // once in 16 bits (at most 765) and added to both halves in the same order as one at a time.
  auto rows8 = [&](std::size_t i) FAULTLINE_TARGET_INLINE("avx2") {
    __m256 v = _mm256_mul_ps(_mm256_set1_ps(f.g[0]), _mm256_loadu_ps(f.rows[0] + i));
    for (int t = 1; t < f.taps; ++t)
      v = _mm256_add_ps(v, _mm256_mul_ps(_mm256_set1_ps(f.g[t]), _mm256_loadu_ps(f.rows[t] + i)));
    return v;
  };
  std::size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    __m256 lo = rows8(i), hi = rows8(i + 8);
    for (int k = 0; k < f.residuals; ++k) {
      auto load = [&](int j) FAULTLINE_TARGET_INLINE("avx2") {
        return _mm256_cvtepu8_epi16(
            _mm_loadu_si128(reinterpret_cast<const __m128i*>(f.residual[3 * k + j] + i)));
      };
      const __m256i sum = _mm256_add_epi16(_mm256_add_epi16(load(0), load(1)), load(2));
      const __m256 w = _mm256_set1_ps(f.residual_w[k]);
      const __m256 sum_lo = _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm256_castsi256_si128(sum)));
      const __m256 sum_hi =
          _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm256_extracti128_si256(sum, 1)));
      lo = _mm256_add_ps(lo, _mm256_mul_ps(w, sum_lo));
      hi = _mm256_add_ps(hi, _mm256_mul_ps(w, sum_hi));
    }
    const __m256 bias = _mm256_set1_ps(f.bias);
    // packs saturate to [0, 255]: the clamp.
    const __m256i words = _mm256_packs_epi32(_mm256_cvttps_epi32(_mm256_add_ps(lo, bias)),
                                             _mm256_cvttps_epi32(_mm256_add_ps(hi, bias)));
    const __m128i bytes =
        _mm_packus_epi16(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), _mm_shuffle_epi32(bytes, 0xD8));
  }
  return i;
}
#endif

void smooth_row(float* h, const std::int32_t* disk, const float* w, int taps, std::size_t n) {
  std::size_t from = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) from = smooth_avx2(h, disk, w, taps, n);
#endif
  smooth_portable(h, disk, w, taps, from, n);
}

void finish_row(std::uint8_t* out, const FinishTaps& f, std::size_t n) {
  std::size_t from = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) from = finish_avx2(out, f, n);
#endif
  finish_portable(out, f, from, n);
}

// Frames too small to pad by the kernel: OpenCV's float32 correlation with the whole kernel.
cv::Mat defocus_small_frame(const cv::Mat& bgr, int severity) {
  const cv::Mat kernel = defocus_kernel(severity);
  cv::Mat filtered;
  cv::filter2D(bgr, filtered, CV_32F, kernel);
  // Kernels summing a hair below 1 (severities 1-3) put the reference's flat areas just below their
  // integer, which truncates one level down; float32 cannot resolve that deficit, so it is applied
  // as a small bias.
  const float bias = cv::sum(kernel)[0] < 1.0 ? -1e-3f : 0.f;
  cv::Mat out(bgr.size(), CV_8UC3);
  const int width = bgr.cols * 3;
  for (int y = 0; y < bgr.rows; ++y) {
    const float* s = filtered.ptr<float>(y);
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < width; ++x)
      o[x] = static_cast<unsigned char>(std::min(std::max(s[x] + bias, 0.f), 255.f));
  }
  return out;
}

}  // namespace

cv::Mat defocus_blur_fast(const cv::Mat& bgr, int severity) {
  const DiskPlan plan = disk_plan(severity);
  const int pad = plan.half + plan.smooth, s = plan.smooth, taps = 2 * s + 1;
  if (bgr.rows <= pad || bgr.cols <= pad) return defocus_small_frame(bgr, severity);
  cv::Mat padded;  // reflect-101, filter2D's border
  cv::copyMakeBorder(bgr, padded, pad, pad, pad, pad, cv::BORDER_REFLECT_101);
  const auto width = static_cast<std::size_t>(bgr.cols) * 3;       // output row
  const auto ext_width = width + 6 * static_cast<std::size_t>(s);  // disk sums, s more each side
  // Disk sums at extended position (ye, xe), centred on padded (ye + half, xe + half): per column
  // dx the run of rows ye + half - run .. ye + half + run. The first row's summed outright, each
  // next one moved down a row (exact integers either way).
  std::vector<std::int32_t> disk(ext_width, 0);
  const int columns = 2 * plan.radius + 1;
  std::vector<const std::uint8_t*> enter(static_cast<std::size_t>(columns)), leave(enter);
  auto column_at = [&](int row, int dx) {
    return padded.ptr<std::uint8_t>(row) + static_cast<std::size_t>(plan.half + dx) * 3;
  };
  for (int dx = -plan.radius; dx <= plan.radius; ++dx) {
    const int run = plan.run[static_cast<std::size_t>(dx + plan.radius)];
    for (int dy = -run; dy <= run; ++dy)
      add_u8(disk.data(), column_at(plan.half + dy, dx), ext_width);
  }
  std::vector<float> h_ring(static_cast<std::size_t>(taps) * width);
  std::vector<float> g(plan.g);
  std::vector<float> gh(plan.g);
  for (float& w : gh) w *= plan.inv_count;
  std::vector<const float*> v_rows(static_cast<std::size_t>(taps));
  std::vector<const std::uint8_t*> residual(plan.residual.size());
  std::vector<float> residual_w;
  for (std::size_t k = 0; k < plan.residual.size(); k += 3)
    residual_w.push_back(plan.residual[k].w);
  const FinishTaps finish{v_rows.data(),   g.data(),          taps,
                          residual.data(), residual_w.data(), static_cast<int>(residual_w.size()),
                          plan.bias};
  cv::Mat out(bgr.size(), CV_8UC3);
  const int ext_rows = bgr.rows + 2 * s;
  for (int ye = 0; ye < ext_rows; ++ye) {
    if (ye > 0) {
      const int centre = ye + plan.half;  // the disk's centre row in the padded frame
      for (int dx = -plan.radius; dx <= plan.radius; ++dx) {
        const auto c = static_cast<std::size_t>(dx + plan.radius);
        enter[c] = column_at(centre + plan.run[c], dx);
        leave[c] = column_at(centre - plan.run[c] - 1, dx);
      }
      disk_step(disk.data(), enter.data(), leave.data(), columns, ext_width);
    }
    float* h = h_ring.data() + static_cast<std::size_t>(ye % taps) * width;
    smooth_row(h, disk.data(), gh.data(), taps, width);
    if (ye < 2 * s) continue;
    const int y = ye - 2 * s;
    for (int t = 0; t < taps; ++t) {
      v_rows[static_cast<std::size_t>(t)] =
          h_ring.data() + static_cast<std::size_t>((y + t) % taps) * width;
    }
    for (std::size_t k = 0; k < plan.residual.size(); ++k) {
      const DiskPlan::Tap& tap = plan.residual[k];
      residual[k] =
          padded.ptr<std::uint8_t>(y + pad + tap.dy) + static_cast<std::size_t>(pad + tap.dx) * 3;
    }
    finish_row(out.ptr<std::uint8_t>(y), finish, width);
  }
  return out;
}

}  // namespace faultline::corruption
