// Snow: normal field -> centre crop -> corner-aligned bilinear zoom -> threshold -> motion blur -> 8-bit layer ->
// whitening blend with the layer added twice.
#include "corruption/snow.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "corruption/motion_blur.hpp"
#include "corruption/motion_kernel.hpp"
#include "corruption/simd_kernels.hpp"
#include "corruption/snow_kernels.hpp"
#include "rng/lane_rng.hpp"

namespace faultline::corruption {
namespace {

struct Crop {
  int top, left, rows, cols;
};

Crop centre_crop(int rows, int cols, double zoom) {
  Crop c{};
  c.rows = std::max(1, static_cast<int>(std::ceil(rows / zoom)));
  c.cols = std::max(1, static_cast<int>(std::ceil(cols / zoom)));
  c.top = (rows - c.rows) / 2;
  c.left = (cols - c.cols) / 2;
  return c;
}

// Corner-aligned linear resampling along one axis: o -> p = o * (n_in - 1) / (n_out - 1).
struct AxisMap {
  std::vector<int> i0, i1;
  std::vector<double> w;
};
AxisMap axis_map(int n_in, int n_out) {
  AxisMap m;
  m.i0.resize(static_cast<std::size_t>(n_out));
  m.i1.resize(static_cast<std::size_t>(n_out));
  m.w.resize(static_cast<std::size_t>(n_out));
  const double ratio = n_out > 1 ? static_cast<double>(n_in - 1) / static_cast<double>(n_out - 1) : 0.0;
  for (int o = 0; o < n_out; ++o) {
    const double p = o * ratio;
    int i = static_cast<int>(std::floor(p));
    i = std::clamp(i, 0, n_in - 1);
    m.i0[static_cast<std::size_t>(o)] = i;
    m.i1[static_cast<std::size_t>(o)] = std::min(i + 1, n_in - 1);
    m.w[static_cast<std::size_t>(o)] = p - i;
  }
  return m;
}

// Zoom (rows first, then columns), threshold and clip. T is double (exact) or float (fast).
template <typename T>
cv::Mat zoom_threshold(const cv::Mat& crop, cv::Size out_size, double threshold) {
  const int depth = cv::DataType<T>::depth;
  const AxisMap rm = axis_map(crop.rows, out_size.height);
  const AxisMap cm = axis_map(crop.cols, out_size.width);
  thread_local cv::Mat tmp;  // reused per thread (avoids page faults on a fresh buffer every frame)
  tmp.create(out_size.height, crop.cols, depth);
  for (int o = 0; o < out_size.height; ++o) {
    const T* a = crop.ptr<T>(rm.i0[static_cast<std::size_t>(o)]);
    const T* b = crop.ptr<T>(rm.i1[static_cast<std::size_t>(o)]);
    const T w = static_cast<T>(rm.w[static_cast<std::size_t>(o)]);
    T* d = tmp.ptr<T>(o);
    for (int x = 0; x < crop.cols; ++x) d[x] = (T(1) - w) * a[x] + w * b[x];
  }
  cv::Mat out(out_size, depth);
  const T thr = static_cast<T>(threshold);
  for (int y = 0; y < out_size.height; ++y) {
    const T* s = tmp.ptr<T>(y);
    T* d = out.ptr<T>(y);
    for (int o = 0; o < out_size.width; ++o) {
      const T w = static_cast<T>(cm.w[static_cast<std::size_t>(o)]);
      T v = (T(1) - w) * s[cm.i0[static_cast<std::size_t>(o)]] + w * s[cm.i1[static_cast<std::size_t>(o)]];
      if (v < thr) v = T(0);
      d[o] = std::min(std::max(v, T(0)), T(1));
    }
  }
  return out;
}

template <typename T>
cv::Mat quantise_crop(const cv::Mat& blurred, int rows, int cols) {
  cv::Mat out(rows, cols, CV_8U);
  for (int y = 0; y < rows; ++y) {
    const T* s = blurred.ptr<T>(y);
    std::uint8_t* d = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < cols; ++x) d[x] = static_cast<std::uint8_t>(std::nearbyint(s[x] * T(255)));
  }
  return out;
}

}  // namespace

SnowParams snow_params(int severity) {
  static constexpr SnowParams kTable[] = {{0.1, 0.3, 3.0, 0.5, 10, 4, 0.8},
                                          {0.2, 0.3, 2.0, 0.5, 12, 4, 0.7},
                                          {0.55, 0.3, 4.0, 0.9, 12, 8, 0.7},
                                          {0.55, 0.3, 4.5, 0.85, 12, 8, 0.65},
                                          {0.55, 0.3, 2.5, 0.85, 12, 12, 0.55}};
  return kTable[std::clamp(severity, 1, 5) - 1];
}

cv::Size snow_layer_size(int rows, int cols, double zoom) {
  const Crop c = centre_crop(rows, cols, zoom);
  return {static_cast<int>(std::nearbyint(c.cols * zoom)), static_cast<int>(std::nearbyint(c.rows * zoom))};
}

cv::Mat snow_layer_exact(const cv::Mat& normals, int severity, double blur_angle_deg) {
  const SnowParams p = snow_params(severity);
  const int rows = normals.rows, cols = normals.cols;
  const Crop c = centre_crop(rows, cols, p.zoom);
  const cv::Mat zoomed = zoom_threshold<double>(normals(cv::Rect(c.left, c.top, c.cols, c.rows)),
                                                snow_layer_size(rows, cols, p.zoom), p.threshold);
  const cv::Mat blurred = blur_layer(zoomed, p.radius, p.sigma, blur_angle_deg);
  return quantise_crop<double>(blurred, rows, cols);
}

namespace {

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define FAULTLINE_FMA_CLONES __attribute__((target_clones("fma", "default")))
#else
#define FAULTLINE_FMA_CLONES
#endif

// One row of the exact blend. The FMA clone turns std::fma into one instruction (same result as the library
// call); contraction stays off, so nothing else is fused.
FAULTLINE_FMA_CLONES void snow_blend_row(const std::uint8_t* src, const std::uint8_t* l, const std::uint8_t* lr,
                                         std::uint8_t* dst, int cols, float b, float one_minus_b) {
  for (int x = 0; x < cols; ++x) {
    const float c0 = static_cast<float>(src[3 * x]) / 255.0f;
    const float c1 = static_cast<float>(src[3 * x + 1]) / 255.0f;
    const float c2 = static_cast<float>(src[3 * x + 2]) / 255.0f;
    // OpenCV's AVX2 RGB2GRAY: fma(ch2, 0.114, fma(ch1, 0.587, ch0 * 0.299)) in float32.
    const float grey = std::fma(c2, 0.114f, std::fma(c1, 0.587f, c0 * 0.299f));
    const float bright = grey * 1.5f + 0.5f;
    const double snow = l[x] / 255.0;
    const double snow_rot = lr[cols - 1 - x] / 255.0;
    const float ch[3] = {c0, c1, c2};
    for (int k = 0; k < 3; ++k) {
      const float whitened = b * ch[k] + one_minus_b * std::max(ch[k], bright);
      const double v = (static_cast<double>(whitened) + snow) + snow_rot;
      dst[3 * x + k] = static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0);
    }
  }
}

}  // namespace

cv::Mat snow_blend_exact(const cv::Mat& bgr, const cv::Mat& layer_u8, int severity) {
  const SnowParams p = snow_params(severity);
  const float b = static_cast<float>(p.blend);
  const float one_minus_b = static_cast<float>(1.0 - p.blend);  // formed in double first, as NumPy does
  const int rows = bgr.rows, cols = bgr.cols;
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < rows; ++y) {
    snow_blend_row(bgr.ptr<std::uint8_t>(y), layer_u8.ptr<std::uint8_t>(y), layer_u8.ptr<std::uint8_t>(rows - 1 - y),
                   out.ptr<std::uint8_t>(y), cols, b, one_minus_b);
  }
  return out;
}

cv::Mat snow_exact(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const SnowParams p = snow_params(severity);
  cv::Mat normals(bgr.rows, bgr.cols, CV_64F);
  for (int y = 0; y < bgr.rows; ++y) {
    double* d = normals.ptr<double>(y);
    for (int x = 0; x < bgr.cols; ++x) d[x] = rng.normal(p.loc, p.scale);
  }
  const double angle = rng.uniform(-135.0, -45.0);
  return snow_blend_exact(bgr, snow_layer_exact(normals, severity, angle), severity);
}

cv::Mat snow_layer_fast(const cv::Mat& crop_field, int rows, int cols, int severity, double blur_angle_deg) {
  // Same stages as the exact layer in float32, reordered for speed: the zoom interpolates columns first (on the few
  // crop rows) and then rows (contiguous); bilinear zoom is separable, so only float rounding differs. The zoomed
  // layer goes straight into an edge-padded buffer, and each blurred row is quantised as soon as it is summed; only
  // the top-left rows x cols are computed.
  const SnowParams p = snow_params(severity);
  const cv::Size size = snow_layer_size(rows, cols, p.zoom);
  const int lh = size.height, lw = size.width;
  const TabulatedKernel* k = find_tabulated_kernel(p.radius, p.sigma);
  const auto offsets = motion_offsets(blur_angle_deg, k->width);
  const int taps = usable_taps(offsets, lh, lw);
  double used = 0.0;
  for (int i = 0; i < taps; ++i) used += k->weights[i];
  const bool scale = taps < k->width && used > 0.0;
  std::vector<float> w(static_cast<std::size_t>(taps));
  int pad = 0;
  for (int i = 0; i < taps; ++i) {
    w[static_cast<std::size_t>(i)] = static_cast<float>(scale ? k->weights[i] / used : k->weights[i]);
    pad = std::max(pad, std::abs(offsets[static_cast<std::size_t>(i)].dx));
  }
  // Column pass on the crop rows.
  const snow_kernels::ColumnZoom column_zoom(crop_field.cols, lw);
  thread_local std::vector<float> colz;  // reused per thread: fresh multi-MB buffers cost page faults
  thread_local std::vector<float> padded;
  const auto lw_u = static_cast<std::size_t>(lw);
  colz.resize(static_cast<std::size_t>(crop_field.rows) * lw_u);
  for (int r = 0; r < crop_field.rows; ++r) {
    column_zoom.run(crop_field.ptr<float>(r), colz.data() + static_cast<std::size_t>(r) * lw_u);
  }
  // Row pass + threshold into the padded layer.
  const snow_kernels::ZoomAxis rm = snow_kernels::zoom_axis(crop_field.rows, lh);
  const std::size_t stride = static_cast<std::size_t>(lw + 2 * pad);
  padded.resize(stride * static_cast<std::size_t>(lh));
  const float thr = static_cast<float>(p.threshold);
  for (int o = 0; o < lh; ++o) {
    const auto ou = static_cast<std::size_t>(o);
    const float* a = colz.data() + static_cast<std::size_t>(rm.i0[ou]) * lw_u;
    const float* b = colz.data() + static_cast<std::size_t>(rm.i1[ou]) * lw_u;
    float* d = padded.data() + ou * stride;
    snow_kernels::lerp_threshold(a, b, rm.w[ou], thr, d + pad, lw);
    std::fill(d, d + pad, d[pad]);
    std::fill(d + pad + lw, d + stride, d[pad + lw - 1]);
  }
  // Blur (edge clamp at the layer's own size) and quantise the top-left rows x cols.
  cv::Mat out(rows, cols, CV_8U);
  std::vector<float> acc(static_cast<std::size_t>(cols));
  std::vector<const float*> src(static_cast<std::size_t>(taps));
  for (int y = 0; y < rows; ++y) {
    for (int i = 0; i < taps; ++i) {
      const auto& o = offsets[static_cast<std::size_t>(i)];
      src[static_cast<std::size_t>(i)] =
          padded.data() + static_cast<std::size_t>(std::clamp(y - o.dy, 0, lh - 1)) * stride + (pad - o.dx);
    }
    simd::weighted_rows(acc.data(), src.data(), w.data(), taps, static_cast<std::size_t>(cols));
    snow_kernels::quantise_row(acc.data(), out.ptr<std::uint8_t>(y), cols);
  }
  return out;
}

cv::Mat snow_blend_fast(const cv::Mat& bgr, const cv::Mat& layer_u8, int severity) {
  const SnowParams p = snow_params(severity);
  const float b = static_cast<float>(p.blend);
  const float one_minus_b = static_cast<float>(1.0 - p.blend);
  const int rows = bgr.rows, cols = bgr.cols;
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < rows; ++y) {
    // The rotated copy is row rows - 1 - y read backwards.
    snow_kernels::blend_fast_row(bgr.ptr<std::uint8_t>(y), layer_u8.ptr<std::uint8_t>(y),
                                 layer_u8.ptr<std::uint8_t>(rows - 1 - y), /*rot_reversed=*/true,
                                 out.ptr<std::uint8_t>(y), cols, b, one_minus_b);
  }
  return out;
}

cv::Mat snow_blend_fast(const cv::Mat& bgr, const cv::Mat& layer_u8, const cv::Mat& layer_rot_u8, int severity) {
  const SnowParams p = snow_params(severity);
  const float b = static_cast<float>(p.blend);
  const float one_minus_b = static_cast<float>(1.0 - p.blend);
  const int rows = bgr.rows, cols = bgr.cols;
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < rows; ++y) {
    snow_kernels::blend_fast_row(bgr.ptr<std::uint8_t>(y), layer_u8.ptr<std::uint8_t>(y),
                                 layer_rot_u8.ptr<std::uint8_t>(y), /*rot_reversed=*/false,
                                 out.ptr<std::uint8_t>(y), cols, b, one_minus_b);
  }
  return out;
}

cv::Mat snow_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const SnowParams p = snow_params(severity);
  const Crop c = centre_crop(bgr.rows, bgr.cols, p.zoom);
  cv::Mat field(c.rows, c.cols, CV_32F);  // continuous
  rng::LaneRng lanes(rng);
  rng::fill_normals(field.ptr<float>(), field.total(), p.loc, p.scale, lanes, rng);
  const double angle = rng.uniform(-135.0, -45.0);
  return snow_blend_fast(bgr, snow_layer_fast(field, bgr.rows, bgr.cols, severity, angle), severity);
}

}  // namespace faultline::corruption
