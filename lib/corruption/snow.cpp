// Snow: normal field -> centre crop -> corner-aligned bilinear zoom -> threshold -> motion blur ->
// 8-bit layer -> whitening blend with the layer added twice.
#include "corruption/snow.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "corruption/motion_kernel.hpp"
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
  const double ratio =
      n_out > 1 ? static_cast<double>(n_in - 1) / static_cast<double>(n_out - 1) : 0.0;
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
  return {static_cast<int>(std::nearbyint(c.cols * zoom)),
          static_cast<int>(std::nearbyint(c.rows * zoom))};
}

namespace {

// What both layer paths share: the zoomed layer's size, the blur kernel, its taps that fit in the
// layer and the edge padding they need.
struct LayerGeometry {
  SnowParams p;
  int lh = 0, lw = 0;
  const TabulatedKernel* kernel = nullptr;
  std::vector<TapOffset> offsets;
  int taps = 0, pad = 0;
};
LayerGeometry layer_geometry(int rows, int cols, int severity, double blur_angle_deg) {
  LayerGeometry g;
  g.p = snow_params(severity);
  const cv::Size size = snow_layer_size(rows, cols, g.p.zoom);
  g.lh = size.height;
  g.lw = size.width;
  g.kernel = find_tabulated_kernel(g.p.radius, g.p.sigma);
  g.offsets = motion_offsets(blur_angle_deg, g.kernel->width);
  g.taps = usable_taps(g.offsets, g.lh, g.lw);
  for (int i = 0; i < g.taps; ++i)
    g.pad = std::max(g.pad, std::abs(g.offsets[static_cast<std::size_t>(i)].dx));
  return g;
}

// The exact layer from the centre crop of the normal field (CV_64F, values N(loc, scale)) for an
// image of rows x cols: zoom rows first and then columns (the reference's order), threshold and
// clip straight into an edge-padded buffer, then blur with the tabulated kernel and round half to
// even to bytes, only for the top-left rows x cols.
cv::Mat layer_exact_from_crop(const cv::Mat& crop, int rows, int cols, int severity,
                              double blur_angle_deg) {
  const LayerGeometry g = layer_geometry(rows, cols, severity, blur_angle_deg);
  const SnowParams& p = g.p;
  const int lh = g.lh, lw = g.lw, taps = g.taps, pad = g.pad;
  const TabulatedKernel* k = g.kernel;
  const auto& offsets = g.offsets;
  const AxisMap rm = axis_map(crop.rows, lh);
  const snow_kernels::ColumnZoom64 column_zoom(crop.cols, lw);
  const std::size_t stride = static_cast<std::size_t>(lw + 2 * pad);
  thread_local std::vector<double> row,
      padded;  // reused per thread: fresh multi-MB buffers cost page faults
  row.resize(static_cast<std::size_t>(crop.cols));
  padded.resize(stride * static_cast<std::size_t>(lh));
  for (int o = 0; o < lh; ++o) {
    const auto ou = static_cast<std::size_t>(o);
    snow_kernels::lerp_row64(crop.ptr<double>(rm.i0[ou]), crop.ptr<double>(rm.i1[ou]), rm.w[ou],
                             row.data(), crop.cols);
    double* d = padded.data() + ou * stride;
    column_zoom.run(row.data(), p.threshold, d + pad);
    std::fill(d, d + pad, d[pad]);
    std::fill(d + pad + lw, d + stride, d[pad + lw - 1]);
  }
  cv::Mat out(rows, cols, CV_8U);
  std::vector<const double*> src(static_cast<std::size_t>(taps));
  for (int y = 0; y < rows; ++y) {
    for (int i = 0; i < taps; ++i) {
      const auto& o = offsets[static_cast<std::size_t>(i)];
      src[static_cast<std::size_t>(i)] =
          padded.data() + static_cast<std::size_t>(std::clamp(y - o.dy, 0, lh - 1)) * stride +
          (pad - o.dx);
    }
    snow_kernels::blur_quantise64(src.data(), k->weights, taps, out.ptr<std::uint8_t>(y),
                                  static_cast<std::size_t>(cols));
  }
  return out;
}

}  // namespace

cv::Mat snow_layer_exact(const cv::Mat& normals, int severity, double blur_angle_deg) {
  const Crop c = centre_crop(normals.rows, normals.cols, snow_params(severity).zoom);
  return layer_exact_from_crop(normals(cv::Rect(c.left, c.top, c.cols, c.rows)), normals.rows,
                               normals.cols, severity, blur_angle_deg);
}

namespace {

// Blends every row with `blend_row` (snow_kernels::blend_exact_row or blend_fast_row). The rotated
// layer's row y is rot's row y, or, when rot_reversed (rot is the layer itself), its row rows - 1 -
// y read backwards.
template <typename BlendRow>
cv::Mat blend_rows(const cv::Mat& bgr, const cv::Mat& layer_u8, const cv::Mat& rot,
                   bool rot_reversed, int severity, BlendRow blend_row) {
  const SnowParams p = snow_params(severity);
  const float b = static_cast<float>(p.blend);
  const float one_minus_b =
      static_cast<float>(1.0 - p.blend);  // formed in double first, as NumPy does
  const int rows = bgr.rows, cols = bgr.cols;
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < rows; ++y) {
    blend_row(bgr.ptr<std::uint8_t>(y), layer_u8.ptr<std::uint8_t>(y),
              rot.ptr<std::uint8_t>(rot_reversed ? rows - 1 - y : y), rot_reversed,
              out.ptr<std::uint8_t>(y), cols, b, one_minus_b);
  }
  return out;
}

const auto kExactRow = [](auto... args) { snow_kernels::blend_exact_row(args...); };
const auto kFastRow = [](auto... args) { snow_kernels::blend_fast_row(args...); };

}  // namespace

cv::Mat snow_blend_exact(const cv::Mat& bgr, const cv::Mat& layer_u8, int severity) {
  return blend_rows(bgr, layer_u8, layer_u8, /*rot_reversed=*/true, severity, kExactRow);
}

cv::Mat snow_exact(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const SnowParams p = snow_params(severity);
  const int rows = bgr.rows, cols = bgr.cols;
  const Crop c = centre_crop(rows, cols, p.zoom);
  // The reference draws H x W normals in row-major order but reads only the centre crop: the others
  // are drawn (same stream, same cache) without being evaluated.
  thread_local cv::Mat crop;
  crop.create(c.rows, c.cols, CV_64F);
  rng.standard_normals(nullptr, static_cast<std::size_t>(c.top) * static_cast<std::size_t>(cols) +
                                    static_cast<std::size_t>(c.left));
  for (int r = 0; r < c.rows; ++r) {
    double* d = crop.ptr<double>(r);
    rng.standard_normals(d, static_cast<std::size_t>(c.cols));
    for (int x = 0; x < c.cols; ++x) d[x] = p.loc + p.scale * d[x];
    const std::size_t rest = r + 1 < c.rows
                                 ? static_cast<std::size_t>(cols - c.cols)
                                 : static_cast<std::size_t>(rows - c.top - c.rows) * cols +
                                       static_cast<std::size_t>(cols - c.left - c.cols);
    rng.standard_normals(nullptr, rest);
  }
  const double angle = rng.uniform(-135.0, -45.0);
  return snow_blend_exact(bgr, layer_exact_from_crop(crop, rows, cols, severity, angle), severity);
}

cv::Mat snow_layer_fast(const cv::Mat& crop_field, int rows, int cols, int severity,
                        double blur_angle_deg) {
  // Same stages as the exact layer, reordered for speed: the zoom interpolates columns first (on
  // the few crop rows) and then rows (contiguous) in float32; bilinear zoom is separable, so only
  // float rounding differs. The blur runs in 16-bit fixed point (within 1 level of the float sum),
  // makes the layer's rows as it needs them (never the whole layer) and quantises each sum at once;
  // only the top-left rows x cols are computed.
  const LayerGeometry g = layer_geometry(rows, cols, severity, blur_angle_deg);
  const SnowParams& p = g.p;
  const int lh = g.lh, lw = g.lw, taps = g.taps;
  const TabulatedKernel* k = g.kernel;
  const auto& offsets = g.offsets;
  double used = 0.0;
  for (int i = 0; i < taps; ++i) used += k->weights[i];
  const bool scale = taps < k->width && used > 0.0;
  std::vector<float> w(static_cast<std::size_t>(taps));
  for (int i = 0; i < taps; ++i) {
    w[static_cast<std::size_t>(i)] =
        static_cast<float>(scale ? k->weights[i] / used : k->weights[i]);
  }
  // Column pass on a crop row when a layer row first reads it, into one of two slots by the row's
  // parity (a layer row reads crop rows i and i + 1, and i never decreases).
  const snow_kernels::ColumnZoom column_zoom(crop_field.cols, lw);
  const auto lw_u = static_cast<std::size_t>(lw);
  thread_local std::vector<float> colz;
  colz.resize(2 * lw_u);
  int zoomed_row[2] = {-1, -1};
  auto column_zoomed = [&](int r) {
    float* d = colz.data() + static_cast<std::size_t>(r & 1) * lw_u;
    if (zoomed_row[r & 1] != r) {
      column_zoom.run(crop_field.ptr<float>(r), d);
      zoomed_row[r & 1] = r;
    }
    return d;
  };
  // Row pass + threshold, made as the blur needs the rows; blur with the edge clamp at the layer's
  // own size, and quantise the top-left rows x cols.
  const snow_kernels::ZoomAxis rm = snow_kernels::zoom_axis(crop_field.rows, lh);
  const float thr = static_cast<float>(p.threshold);
  const snow_kernels::LayerRowMaker make_row = [&](int o, std::uint16_t* d) {
    const auto ou = static_cast<std::size_t>(o);
    const float* a = column_zoomed(rm.i0[ou]);
    const float* b = column_zoomed(rm.i1[ou]);
    snow_kernels::lerp_threshold_u16(a, b, rm.w[ou], thr, d, lw);
  };
  std::vector<int> dx(static_cast<std::size_t>(taps)), dy(static_cast<std::size_t>(taps));
  for (int i = 0; i < taps; ++i) {
    dx[static_cast<std::size_t>(i)] = offsets[static_cast<std::size_t>(i)].dx;
    dy[static_cast<std::size_t>(i)] = offsets[static_cast<std::size_t>(i)].dy;
  }
  cv::Mat out(rows, cols, CV_8U);
  snow_kernels::blur_quantise(make_row, lh, lw, dx.data(), dy.data(), w.data(), taps,
                              out.ptr<std::uint8_t>(), out.step[0], rows, cols);
  return out;
}

cv::Mat snow_blend_fast(const cv::Mat& bgr, const cv::Mat& layer_u8, int severity) {
  return blend_rows(bgr, layer_u8, layer_u8, /*rot_reversed=*/true, severity, kFastRow);
}

cv::Mat snow_blend_fast(const cv::Mat& bgr, const cv::Mat& layer_u8, const cv::Mat& layer_rot_u8,
                        int severity) {
  return blend_rows(bgr, layer_u8, layer_rot_u8, /*rot_reversed=*/false, severity, kFastRow);
}

cv::Mat snow_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const SnowParams p = snow_params(severity);
  const Crop c = centre_crop(bgr.rows, bgr.cols, p.zoom);
  cv::Mat field(c.rows, c.cols, CV_32F);  // continuous
  rng::LaneRng lanes(rng);
  rng::fill_normals(field.ptr<float>(), field.total(), p.loc, p.scale, lanes, rng);
  const double angle = rng.uniform(-135.0, -45.0);
  return snow_blend_fast(bgr, snow_layer_fast(field, bgr.rows, bgr.cols, severity, angle),
                         severity);
}

}  // namespace faultline::corruption
