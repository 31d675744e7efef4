// Elastic Transform: the reference's smoothed random field and float64 bilinear resampling; a
// low-resolution fast path.
#include "corruption/elastic_transform.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/simd.hpp"
#include "corruption/ndimage.hpp"

namespace faultline::corruption {

namespace {

// ndimage's map_coordinate for mode 'reflect' (boundary code 2), as SciPy 1.10 writes it.
double map_reflect(double in, int len) {
  if (in < 0) {
    if (len <= 1) return 0;
    const double sz2 = 2.0 * len;
    if (in < -sz2) in = sz2 * static_cast<double>(static_cast<long long>(-in / sz2)) + in;
    in = in < -len ? in + sz2 : (in > -1e-15 ? 1e-15 : -in) - 1;
  } else if (in > len - 1) {
    if (len <= 1) return 0;
    const double sz2 = 2.0 * len;
    in -= sz2 * static_cast<double>(static_cast<long long>(in / sz2));
    if (in >= len) in = sz2 - in - 1;
  }
  return in;
}

// One axis of the order-1 footprint: two source indices and their weights.
struct Taps {
  int i0, i1;
  double w0, w1;
};

Taps taps_reflect(double coord, int len) {
  const double cc = map_reflect(coord, len);
  Taps t;
  const double f = std::floor(cc);
  const int start = static_cast<int>(f);
  const double x = cc - f;
  t.w0 = 1.0 - x;
  t.w1 = 1.0 - t.w0;
  // Taps outside the line are mapped back with the same reflection (integer positions).
  t.i0 = start < 0 || start >= len ? static_cast<int>(map_reflect(start, len)) : start;
  t.i1 =
      start + 1 >= len || start + 1 < 0 ? static_cast<int>(map_reflect(start + 1, len)) : start + 1;
  return t;
}

cv::Mat smoothed_field(int rows, int cols, double max_d, double alpha, rng::NumpyRandomState& rng) {
  cv::Mat f(rows, cols, CV_64F);
  for (int y = 0; y < rows; ++y) {
    double* p = f.ptr<double>(y);
    for (int x = 0; x < cols; ++x) p[x] = rng.uniform(-max_d, max_d);
  }
  nd::gaussian_filter(f, rows * 0.01, cols * 0.01, nd::Extend::Reflect, 3.0);
  cv::Mat out(rows, cols, CV_32F);
  for (int y = 0; y < rows; ++y) {
    const double* p = f.ptr<double>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < cols; ++x) o[x] = static_cast<float>(p[x] * alpha);
  }
  return out;
}

}  // namespace

double elastic_alpha(int severity) {
  static const double kAlpha[] = {250 * 0.05, 250 * 0.065, 250 * 0.085, 250 * 0.1, 250 * 0.12};
  return kAlpha[severity - 1];
}

void elastic_fields_numpy(int rows, int cols, int severity, rng::NumpyRandomState& rng, cv::Mat& dx,
                          cv::Mat& dy) {
  const double max_d = rows * 0.005;
  dx = smoothed_field(rows, cols, max_d, elastic_alpha(severity), rng);
  dy = smoothed_field(rows, cols, max_d, elastic_alpha(severity), rng);
}

cv::Mat elastic_transform_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const int rows = bgr.rows, cols = bgr.cols;
  cv::Mat image(bgr.size(), CV_32FC3);
  for (int y = 0; y < rows; ++y) {
    const unsigned char* s = bgr.ptr<unsigned char>(y);
    float* d = image.ptr<float>(y);
    for (int i = 0; i < cols * 3; ++i) d[i] = static_cast<float>(s[i]) / 255.f;  // float32 / 255.
  }
  cv::Mat dx, dy;
  elastic_fields_numpy(rows, cols, severity, rng, dx, dy);
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < rows; ++y) {
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < cols; ++x) {
      const Taps ty =
          taps_reflect(static_cast<double>(y) + static_cast<double>(dy.at<float>(y, x)), rows);
      const Taps tx =
          taps_reflect(static_cast<double>(x) + static_cast<double>(dx.at<float>(y, x)), cols);
      const float* r0 = image.ptr<float>(ty.i0);
      const float* r1 = image.ptr<float>(ty.i1);
      for (int c = 0; c < 3; ++c) {
        // The 2 x 2 x 2 footprint in C order; the channel axis's second tap has weight 0 and adds
        // +0.
        double t = 0.0;
        t += static_cast<double>(r0[3 * tx.i0 + c]) * ty.w0 * tx.w0;
        t += static_cast<double>(r0[3 * tx.i1 + c]) * ty.w0 * tx.w1;
        t += static_cast<double>(r1[3 * tx.i0 + c]) * ty.w1 * tx.w0;
        t += static_cast<double>(r1[3 * tx.i1 + c]) * ty.w1 * tx.w1;
        const float v = static_cast<float>(t);
        o[3 * x + c] = static_cast<unsigned char>(std::min(std::max(v, 0.f), 1.f) * 255.f);
      }
    }
  }
  return out;
}

namespace {

// Sum of squared weights of a symmetric kernel given by its half (offset 0..r): the variance gain
// on white noise.
double square_sum(const std::vector<double>& half) {
  double s = half[0] * half[0];
  for (std::size_t k = 1; k < half.size(); ++k) s += 2 * half[k] * half[k];
  return s;
}

cv::Mat as_column(const std::vector<double>& half) {
  const int r = static_cast<int>(half.size()) - 1;
  cv::Mat k(2 * r + 1, 1, CV_32F);
  for (int i = -r; i <= r; ++i)
    k.at<float>(i + r) = static_cast<float>(half[static_cast<std::size_t>(std::abs(i))]);
  return k;
}

// OpenCV's bilinear resize taps along one axis (pixel centres: (i + 0.5) n_in / n_out - 0.5,
// clamped to the first and last sample).
struct ResizeTap {
  int first, second;
  float weight;  // of second
};

std::vector<ResizeTap> resize_taps(int n_in, int n_out) {
  std::vector<ResizeTap> taps(static_cast<std::size_t>(n_out));
  const double scale = static_cast<double>(n_in) / n_out;
  for (int i = 0; i < n_out; ++i) {
    const double c = (i + 0.5) * scale - 0.5;
    auto first = static_cast<int>(std::floor(c));
    float w = static_cast<float>(c - first);
    if (first < 0) first = 0, w = 0.f;
    if (first >= n_in - 1) first = n_in - 1, w = 0.f;
    taps[static_cast<std::size_t>(i)] = {first, std::min(first + 1, n_in - 1), w};
  }
  return taps;
}

// One row of remap's fixed-point maps from the displacement rows: the source position (x + dx,
// y + dy) in 1/32 pixel (cv::INTER_TAB_SIZE), rounded to nearest even as cv::convertMaps does, its
// integer part (saturated to 16 bits) and its fraction's table index.
void fixed_point_tail(std::int16_t* xy, std::uint16_t* frac, const float* dx, const float* dy,
                      float y, std::size_t from, std::size_t cols) {
  for (std::size_t x = from; x < cols; ++x) {
    const auto ix =
        static_cast<std::int32_t>(std::nearbyint((static_cast<float>(x) + dx[x]) * 32.f));
    const auto iy = static_cast<std::int32_t>(std::nearbyint((y + dy[x]) * 32.f));
    xy[2 * x] = static_cast<std::int16_t>(std::clamp(ix >> 5, -32768, 32767));
    xy[2 * x + 1] = static_cast<std::int16_t>(std::clamp(iy >> 5, -32768, 32767));
    frac[x] = static_cast<std::uint16_t>((iy & 31) * 32 + (ix & 31));
  }
}

#if FAULTLINE_X86_SIMD
FAULTLINE_TARGET("avx2")
std::size_t fixed_point_avx2(std::int16_t* xy, std::uint16_t* frac, const float* dx,
                             const float* dy, float y, std::size_t cols) {
  const __m256 lanes = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7), k32 = _mm256_set1_ps(32.f);
  const __m256 yv = _mm256_set1_ps(y);
  const __m256i lo = _mm256_set1_epi32(-32768), hi = _mm256_set1_epi32(32767);
  const __m256i low5 = _mm256_set1_epi32(31), low16 = _mm256_set1_epi32(0xFFFF);
  std::size_t x = 0;
  for (; x + 8 <= cols; x += 8) {
    const __m256 px = _mm256_add_ps(_mm256_set1_ps(static_cast<float>(x)), lanes);
    const __m256i ix =
        _mm256_cvtps_epi32(_mm256_mul_ps(_mm256_add_ps(px, _mm256_loadu_ps(dx + x)), k32));
    const __m256i iy =
        _mm256_cvtps_epi32(_mm256_mul_ps(_mm256_add_ps(yv, _mm256_loadu_ps(dy + x)), k32));
    const __m256i qx = _mm256_min_epi32(_mm256_max_epi32(_mm256_srai_epi32(ix, 5), lo), hi);
    const __m256i qy = _mm256_min_epi32(_mm256_max_epi32(_mm256_srai_epi32(iy, 5), lo), hi);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(xy + 2 * x),
                        _mm256_or_si256(_mm256_and_si256(qx, low16), _mm256_slli_epi32(qy, 16)));
    const __m256i f = _mm256_or_si256(_mm256_slli_epi32(_mm256_and_si256(iy, low5), 5),
                                      _mm256_and_si256(ix, low5));
    const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi32(f, f), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(frac + x), _mm256_castsi256_si128(packed));
  }
  return x;
}
#endif

void fixed_point_row(std::int16_t* xy, std::uint16_t* frac, const float* dx, const float* dy,
                     float y, std::size_t cols) {
  std::size_t from = 0;
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) from = fixed_point_avx2(xy, frac, dx, dy, y, cols);
#endif
  fixed_point_tail(xy, frac, dx, dy, y, from, cols);
}

// One low-resolution field row across to the frame's columns.
void widen_row(float* out, const float* in, const std::vector<ResizeTap>& taps) {
  for (std::size_t x = 0; x < taps.size(); ++x) {
    const ResizeTap& t = taps[x];
    out[x] = in[t.first] + t.weight * (in[t.second] - in[t.first]);
  }
}

// (1 - w) a + w b.
FAULTLINE_CLONES("avx2")
void blend_rows(float* out, const float* a, const float* b, float w, std::size_t n) {
  for (std::size_t x = 0; x < n; ++x) out[x] = a[x] + w * (b[x] - a[x]);
}

// The frame resampled at (x + dx, y + dy), the displacements the low-resolution fields scaled up
// bilinearly: remap's fixed-point maps built a band of rows at a time (kept in cache; float maps
// of the whole frame cost four frame-sized passes and remap converts them again).
cv::Mat remap_by_field(const cv::Mat& bgr, const cv::Mat (&low)[2]) {
  const int rows = bgr.rows, cols = bgr.cols;
  const auto across = resize_taps(low[0].cols, cols), down = resize_taps(low[0].rows, rows);
  // The fields widened to the frame's columns once per low-resolution row (a quarter of the rows).
  cv::Mat wide[2];
  for (int f = 0; f < 2; ++f) {
    wide[f].create(low[f].rows, cols, CV_32F);
    for (int y = 0; y < low[f].rows; ++y)
      widen_row(wide[f].ptr<float>(y), low[f].ptr<float>(y), across);
  }
  constexpr int kBand = 16;
  cv::Mat xy(kBand, cols, CV_16SC2), frac(kBand, cols, CV_16UC1);
  std::vector<float> dx(static_cast<std::size_t>(cols)), dy(dx);
  const auto n = static_cast<std::size_t>(cols);
  cv::Mat out(bgr.size(), bgr.type());
  for (int top = 0; top < rows; top += kBand) {
    const int band = std::min(kBand, rows - top);
    for (int i = 0; i < band; ++i) {
      const ResizeTap& t = down[static_cast<std::size_t>(top + i)];
      blend_rows(dx.data(), wide[0].ptr<float>(t.first), wide[0].ptr<float>(t.second), t.weight, n);
      blend_rows(dy.data(), wide[1].ptr<float>(t.first), wide[1].ptr<float>(t.second), t.weight, n);
      fixed_point_row(xy.ptr<std::int16_t>(i), frac.ptr<std::uint16_t>(i), dx.data(), dy.data(),
                      static_cast<float>(top + i), n);
    }
    cv::Mat dst = out.rowRange(top, top + band);
    cv::remap(bgr, dst, xy.rowRange(0, band), frac.rowRange(0, band), cv::INTER_LINEAR,
              cv::BORDER_REFLECT);
  }
  return out;
}

}  // namespace

cv::Mat elastic_transform_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const int rows = bgr.rows, cols = bgr.cols;
  // The field is smooth (sigma 1 % of the frame), so it is drawn and smoothed on a grid `factor`
  // times coarser with sigma / factor, then interpolated up. White noise smoothed there keeps more
  // variance; the field is rescaled so that its standard deviation equals the full-resolution
  // field's (ratio of the kernels' squared sums).
  const int factor = std::max(1, std::min({4, rows / 8, cols / 8}));
  const int lr = std::max(1, rows / factor), lc = std::max(1, cols / factor);
  const double max_d = rows * 0.005, sy = rows * 0.01, sx = cols * 0.01;
  const auto ky = nd::gaussian_kernel(sy, nd::gaussian_radius(sy, 3.0));
  const auto kx = nd::gaussian_kernel(sx, nd::gaussian_radius(sx, 3.0));
  const double ly = sy * lr / rows, lx = sx * lc / cols;
  const auto kly = nd::gaussian_kernel(ly, nd::gaussian_radius(ly, 3.0));
  const auto klx = nd::gaussian_kernel(lx, nd::gaussian_radius(lx, 3.0));
  const double scale = elastic_alpha(severity) * std::sqrt(square_sum(ky) * square_sum(kx) /
                                                           (square_sum(kly) * square_sum(klx)));
  cv::Mat low[2];
  for (auto& m : low) {
    m.create(lr, lc, CV_32F);
    for (int y = 0; y < lr; ++y) {
      float* p = m.ptr<float>(y);
      for (int x = 0; x < lc; ++x) p[x] = static_cast<float>(rng.uniform(-max_d, max_d));
    }
    cv::sepFilter2D(m, m, CV_32F, as_column(klx), as_column(kly), cv::Point(-1, -1), 0,
                    cv::BORDER_REFLECT);
    m *= scale;
  }
  return remap_by_field(bgr, low);
}

}  // namespace faultline::corruption
