// Diamond-square on a torus with the reference's pass order and bracketing, and the fog blend.
#include "corruption/fog.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace faultline::corruption {
namespace {

// Returns the normalised top-left rows x cols crop of the plasma map (the full map when rows = cols = mapsize).
// Level by level: the corner grid of step s (n x n) plus the three passes' points form the corner grid of step
// s/2 (2n x 2n), written sequentially instead of strided into an N x N map. The last level only tracks min/max
// and keeps the crop. Same draws, same sums, same doubles as the reference's in-place map.
template <typename Rng>
cv::Mat plasma_impl(int mapsize, double decay, Rng& rng, int crop_rows, int crop_cols) {
  std::vector<double> corner(1, 0.0), centre, next;
  cv::Mat out(crop_rows, crop_cols, CV_64F, cv::Scalar(0.0));
  double mn = 0.0, mx = 0.0;  // M[0,0] = 0 is part of the map
  int n = 1;
  double w = 100.0;
  if (mapsize == 1) return out;
  auto idx = [](int r, int c, int stride) {
    return static_cast<std::size_t>(r) * static_cast<std::size_t>(stride) + static_cast<std::size_t>(c);
  };
  while (n < mapsize) {
    const int n2 = 2 * n;
    const bool last = n2 == mapsize;
    const double lo = -w, span = w - (-w);
    auto next_i = [n](int i) { return i + 1 == n ? 0 : i + 1; };
    auto prev_i = [n](int i) { return i == 0 ? n - 1 : i - 1; };
    auto put = [&](int r, int c, double v) {
      if (last) {
        mn = std::min(mn, v);
        mx = std::max(mx, v);
        if (r < crop_rows && c < crop_cols) out.at<double>(r, c) = v;
      } else {
        next[idx(r, c, n2)] = v;
      }
    };
    if (!last) next.assign(static_cast<std::size_t>(n2) * static_cast<std::size_t>(n2), 0.0);
    // Squares: centres from the four corners.
    centre.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      const double* c0 = &corner[idx(i, 0, n)];
      const double* c1 = &corner[idx(next_i(i), 0, n)];
      double* d = &centre[idx(i, 0, n)];
      for (int j = 0; j < n; ++j) {
        const int j1 = next_i(j);
        d[j] = ((c0[j] + c1[j]) + (c0[j1] + c1[j1])) / 4 + w * (lo + span * rng.random_sample());
      }
    }
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        put(2 * i, 2 * j, corner[idx(i, j, n)]);
        put(2 * i + 1, 2 * j + 1, centre[idx(i, j, n)]);
      }
    }
    // Diamonds, horizontal-edge points (use the new centres).
    for (int i = 0; i < n; ++i) {
      const double* d0 = &centre[idx(i, 0, n)];
      const double* dp = &centre[idx(prev_i(i), 0, n)];
      const double* c0 = &corner[idx(i, 0, n)];
      for (int j = 0; j < n; ++j) {
        const double sum = (d0[j] + dp[j]) + (c0[j] + c0[next_i(j)]);
        put(2 * i, 2 * j + 1, sum / 4 + w * (lo + span * rng.random_sample()));
      }
    }
    // Diamonds, vertical-edge points (do not read the horizontal-edge points).
    for (int i = 0; i < n; ++i) {
      const double* d0 = &centre[idx(i, 0, n)];
      const double* c0 = &corner[idx(i, 0, n)];
      const double* c1 = &corner[idx(next_i(i), 0, n)];
      for (int j = 0; j < n; ++j) {
        const double sum = (d0[j] + d0[prev_i(j)]) + (c0[j] + c1[j]);
        put(2 * i + 1, 2 * j, sum / 4 + w * (lo + span * rng.random_sample()));
      }
    }
    if (!last) corner.swap(next);
    n = n2;
    w /= decay;
  }
  const double range = mx - mn;  // == max(M - min) exactly: subtraction is monotone
  for (int r = 0; r < crop_rows; ++r) {
    double* p = out.ptr<double>(r);
    for (int c = 0; c < crop_cols; ++c) p[c] = (p[c] - mn) / range;
  }
  return out;
}

}  // namespace

FogParams fog_params(int severity) {
  static constexpr FogParams kTable[] = {{1.5, 2.0}, {2.0, 2.0}, {2.5, 1.7}, {2.5, 1.5}, {3.0, 1.4}};
  return kTable[std::clamp(severity, 1, 5) - 1];
}

int fog_map_size(int rows, int cols) {
  const int side = std::max({rows, cols, 3});
  int n = 1;
  while (n < side) n *= 2;
  return n;
}

cv::Mat plasma_fractal(int mapsize, double decay, rng::NumpyRandomState& rng) {
  return plasma_impl(mapsize, decay, rng, mapsize, mapsize);
}
cv::Mat plasma_fractal(int mapsize, double decay, rng::FastRng& rng) {
  return plasma_impl(mapsize, decay, rng, mapsize, mapsize);
}
cv::Mat plasma_fractal_crop(int mapsize, double decay, rng::NumpyRandomState& rng, int rows, int cols) {
  return plasma_impl(mapsize, decay, rng, rows, cols);
}

cv::Mat fog_blend_exact(const cv::Mat& bgr, const cv::Mat& fractal, double strength) {
  double max_u8 = 0.0;
  cv::minMaxLoc(bgr.reshape(1), nullptr, &max_u8);
  const double m = max_u8 / 255.0;
  const double denom = m + strength;
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < bgr.rows; ++y) {
    const std::uint8_t* src = bgr.ptr<std::uint8_t>(y);
    const double* f = fractal.ptr<double>(y);
    std::uint8_t* dst = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      const double add = strength * f[x];
      for (int c = 0; c < 3; ++c) {
        const double v = src[3 * x + c] / 255.0 + add;
        const double r = (v * m) / denom;
        dst[3 * x + c] = static_cast<std::uint8_t>(std::min(std::max(r, 0.0), 1.0) * 255.0);
      }
    }
  }
  return out;
}

namespace {

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define FAULTLINE_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FAULTLINE_AVX2_CLONES
#endif

// One row of the fast blend, straight-line over the three interleaved channels so that GCC vectorises it.
FAULTLINE_AVX2_CLONES void fog_blend_fast_row(const std::uint8_t* __restrict src, const float* __restrict f,
                                              std::uint8_t* __restrict dst, int cols, float scale, float add_scale) {
  for (int x = 0; x < cols; ++x) {
    const float a = add_scale * f[x];
    const float v0 = static_cast<float>(src[3 * x]) * scale + a;
    const float v1 = static_cast<float>(src[3 * x + 1]) * scale + a;
    const float v2 = static_cast<float>(src[3 * x + 2]) * scale + a;
    dst[3 * x] = static_cast<std::uint8_t>(static_cast<int>(std::min(std::max(v0, 0.0f), 255.0f)));
    dst[3 * x + 1] = static_cast<std::uint8_t>(static_cast<int>(std::min(std::max(v1, 0.0f), 255.0f)));
    dst[3 * x + 2] = static_cast<std::uint8_t>(static_cast<int>(std::min(std::max(v2, 0.0f), 255.0f)));
  }
}

}  // namespace

cv::Mat fog_blend_fast(const cv::Mat& bgr, const cv::Mat& field, double strength) {
  double max_u8 = 0.0;
  cv::minMaxLoc(bgr.reshape(1), nullptr, &max_u8);
  const float m = static_cast<float>(max_u8 / 255.0);
  const float scale = m / (m + static_cast<float>(strength));  // applied in the 0..255 domain
  const float add_scale = static_cast<float>(strength) * 255.0f * scale;
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < bgr.rows; ++y) {
    fog_blend_fast_row(bgr.ptr<std::uint8_t>(y), field.ptr<float>(y), out.ptr<std::uint8_t>(y), bgr.cols, scale,
                       add_scale);
  }
  return out;
}

cv::Mat upsample_torus_window(const cv::Mat& low, int factor, double row0, double col0, int rows, int cols) {
  cv::Mat low32;
  low.convertTo(low32, CV_32F);
  const int n_r = low32.rows, n_c = low32.cols;
  // Separable bilinear with wrap: build per-axis source coordinates, then remap over a wrapped border.
  cv::Mat padded;
  const int pad = 2;
  cv::copyMakeBorder(low32, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
  cv::Mat xs(rows, cols, CV_32F), ys(rows, cols, CV_32F);
  std::vector<float> cx(static_cast<std::size_t>(cols));
  for (int x = 0; x < cols; ++x) {
    double s = std::fmod((col0 + x) / factor, static_cast<double>(n_c));
    if (s < 0) s += n_c;
    cx[static_cast<std::size_t>(x)] = static_cast<float>(s + pad);
  }
  for (int y = 0; y < rows; ++y) {
    double s = std::fmod((row0 + y) / factor, static_cast<double>(n_r));
    if (s < 0) s += n_r;
    const float sy = static_cast<float>(s + pad);
    float* px = xs.ptr<float>(y);
    float* py = ys.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      px[x] = cx[static_cast<std::size_t>(x)];
      py[x] = sy;
    }
  }
  cv::Mat out;
  cv::remap(padded, out, xs, ys, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

cv::Mat fog_field_fast(int rows, int cols, double decay, rng::FastRng& rng) {
  const int n = fog_map_size(rows, cols);
  const int factor = n >= 64 ? 4 : 1;
  const cv::Mat low = plasma_impl(n / factor, decay, rng, n / factor, n / factor);
  if (factor == 1) {
    cv::Mat out;
    low(cv::Rect(0, 0, cols, rows)).convertTo(out, CV_32F);
    return out;
  }
  // Coarse grid row i sits at full-resolution row factor * i, as in the full map.
  const int lr = std::min(low.rows, rows / factor + 2), lc = std::min(low.cols, cols / factor + 2);
  cv::Mat crop;
  low(cv::Rect(0, 0, lc, lr)).convertTo(crop, CV_32F);
  cv::Mat up;
  cv::resize(crop, up, cv::Size(lc * factor, lr * factor), 0, 0, cv::INTER_LINEAR);
  if (up.rows < rows || up.cols < cols) {
    return upsample_torus_window(low, factor, 0.0, 0.0, rows, cols);
  }
  return up(cv::Rect(0, 0, cols, rows));  // a view: no 5.8 MB copy per frame (rows are read by pointer)
}

}  // namespace faultline::corruption
