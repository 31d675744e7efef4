// Elastic Transform: the reference's smoothed random field and float64 bilinear resampling; a
// low-resolution fast path.
#include "corruption/elastic_transform.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

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
  cv::Mat maps[2];
  for (auto& m : maps) {
    cv::Mat low(lr, lc, CV_32F);
    for (int y = 0; y < lr; ++y) {
      float* p = low.ptr<float>(y);
      for (int x = 0; x < lc; ++x) p[x] = static_cast<float>(rng.uniform(-max_d, max_d));
    }
    cv::sepFilter2D(low, low, CV_32F, as_column(klx), as_column(kly), cv::Point(-1, -1), 0,
                    cv::BORDER_REFLECT);
    cv::resize(low, m, bgr.size(), 0, 0, cv::INTER_LINEAR);
    m *= scale;
  }
  cv::Mat mx(bgr.size(), CV_32F), my(bgr.size(), CV_32F);
  for (int y = 0; y < rows; ++y) {
    const float* dx = maps[0].ptr<float>(y);
    const float* dy = maps[1].ptr<float>(y);
    float* px = mx.ptr<float>(y);
    float* py = my.ptr<float>(y);
    for (int x = 0; x < cols; ++x)
      px[x] = static_cast<float>(x) + dx[x], py[x] = static_cast<float>(y) + dy[x];
  }
  cv::Mat out;
  cv::remap(bgr, out, mx, my, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

}  // namespace faultline::corruption
