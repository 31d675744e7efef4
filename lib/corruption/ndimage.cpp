// NumPy exp and sum, SciPy ndimage Gaussian filter and linear zoom, as the reference evaluates
// them.
#include "corruption/ndimage.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "common/simd.hpp"

namespace faultline::corruption::nd {

namespace {

// SVML's 2^(j/16) table (__svml_exp8, the version NumPy 1.24 links on AVX-512 CPUs).
constexpr double kExpTable[16] = {
    0x1.0000000000000p+0, 0x1.0b5586cf9890fp+0, 0x1.172b83c7d517bp+0, 0x1.2387a6e756238p+0,
    0x1.306fe0a31b715p+0, 0x1.3dea64c123422p+0, 0x1.4bfdad5362a27p+0, 0x1.5ab07dd485429p+0,
    0x1.6a09e667f3bcdp+0, 0x1.7a11473eb0187p+0, 0x1.8ace5422aa0dbp+0, 0x1.9c49182a3f090p+0,
    0x1.ae89f995ad3adp+0, 0x1.c199bdd85529cp+0, 0x1.d5818dcfba487p+0, 0x1.ea4afa2a490dap+0};

std::uint64_t to_bits(double d) {
  std::uint64_t b;
  std::memcpy(&b, &d, sizeof b);
  return b;
}

// One symmetric correlation pass as ndimage's NI_Correlate1D evaluates it: acc = x[i] * w[0], then
// the pairs from the outermost in, acc += (x[i - k] + x[i + k]) * w[k]. `w[k]` is the weight at
// offset k (0..radius).
void correlate_line(const double* ext, int n, int radius, const std::vector<double>& w,
                    double* out) {
  for (int i = 0; i < n; ++i) {
    const double* x = ext + radius + i;
    double acc = x[0] * w[0];
    for (int k = radius; k >= 1; --k) acc += (x[-k] + x[k]) * w[static_cast<std::size_t>(k)];
    out[i] = acc;
  }
}

// Axis 0 (down the columns) of a H x (W*C) double array.
void correlate_rows(const cv::Mat& in, cv::Mat& out, const std::vector<double>& w, Extend mode) {
  const int radius = static_cast<int>(w.size()) - 1;
  const int rows = in.rows, width = in.cols * in.channels();
  std::vector<const double*> src(static_cast<std::size_t>(rows + 2 * radius));
  for (int i = -radius; i < rows + radius; ++i) {
    src[static_cast<std::size_t>(i + radius)] = in.ptr<double>(extend_index(i, rows, mode));
  }
  for (int i = 0; i < rows; ++i) {
    double* o = out.ptr<double>(i);
    const double* c = src[static_cast<std::size_t>(i + radius)];
    for (int x = 0; x < width; ++x) o[x] = c[x] * w[0];
    for (int k = radius; k >= 1; --k) {
      const double* a = src[static_cast<std::size_t>(i + radius - k)];
      const double* b = src[static_cast<std::size_t>(i + radius + k)];
      const double wk = w[static_cast<std::size_t>(k)];
      for (int x = 0; x < width; ++x) o[x] += (a[x] + b[x]) * wk;
    }
  }
}

// Axis 1 (along the rows) of a H x W x C double array.
void correlate_cols(const cv::Mat& in, cv::Mat& out, const std::vector<double>& w, Extend mode) {
  const int radius = static_cast<int>(w.size()) - 1;
  const int cols = in.cols, ch = in.channels();
  std::vector<double> ext(static_cast<std::size_t>(cols + 2 * radius)),
      line(static_cast<std::size_t>(cols));
  for (int y = 0; y < in.rows; ++y) {
    const double* s = in.ptr<double>(y);
    double* o = out.ptr<double>(y);
    for (int c = 0; c < ch; ++c) {
      for (int i = -radius; i < cols + radius; ++i) {
        ext[static_cast<std::size_t>(i + radius)] = s[extend_index(i, cols, mode) * ch + c];
      }
      correlate_line(ext.data(), cols, radius, w, line.data());
      for (int x = 0; x < cols; ++x) o[x * ch + c] = line[static_cast<std::size_t>(x)];
    }
  }
}

// Rounds every value to float32 and back: the pass's result as stored in a float32 output array.
void round_to_float(cv::Mat& m) {
  const int width = m.cols * m.channels();
  for (int y = 0; y < m.rows; ++y) {
    double* p = m.ptr<double>(y);
    for (int x = 0; x < width; ++x) p[x] = static_cast<double>(static_cast<float>(p[x]));
  }
}

}  // namespace

double numpy_exp(double x) {
  // NumPy 1.24 evaluates float64 exp with Intel SVML's __svml_exp8 on AVX-512 CPUs; this is its
  // main path step by step (FMA where it has FMA). Arguments beyond its range check (|x| > ~707.7,
  // NaN) take SVML's slow path, for which libm's exp stands in.
  if (!(std::fabs(x) <= 0x1.61da04cbafe44p+9)) return std::exp(x);
  const double log2e = 0x1.71547652b82fep+0, shifter = 0x1.8000000003ff0p+48;
  // x * log2(e) + shifter rounded toward zero: the round-to-nearest FMA, stepped down when it
  // rounded up (the sign of the exact remainder comes from a second FMA).
  double s = std::fma(x, log2e, shifter);
  if (std::fma(x, log2e, -(s - shifter)) < 0) s = std::nextafter(s, 0.0);
  const double n = s - shifter;  // x * log2(e) truncated to 1/16
  const double th = kExpTable[to_bits(s) & 15u];
  double r = std::fma(-n, 0x1.62e42fefa39efp-1, x);
  r = std::fma(-n, 0x1.abc9e3b39803fp-56, r);
  const double r2 = r * r;
  const double p56 = std::fma(0x1.72eb5ef0d213dp-10, r, 0x1.1106603d97c00p-7);
  const double p34 = std::fma(0x1.555564bb4f5f0p-5, r, 0x1.5555554b508a2p-3);
  const double r3 = r2 * r;
  const double p12 = std::fma(r2, 0x1.0000000002622p-1, r);
  const double p36 = std::fma(r2, p56, p34);
  const double p16 = std::fma(r3, p36, p12);
  return std::ldexp(std::fma(th, p16, th), static_cast<int>(std::floor(n)));  // vscalefpd
}

int gaussian_radius(double sigma, double truncate) {
  return static_cast<int>(truncate * sigma + 0.5);
}

std::vector<double> gaussian_kernel(double sigma, int radius) {
  const double scale = -0.5 / (sigma * sigma);
  std::vector<double> phi(static_cast<std::size_t>(2 * radius + 1));
  for (int x = -radius; x <= radius; ++x) {
    phi[static_cast<std::size_t>(x + radius)] = numpy_exp(scale * static_cast<double>(x * x));
  }
  const double sum =
      0.0 + pairwise_sum(phi.data(), phi.size());  // add.reduce starts from its identity
  std::vector<double> w(static_cast<std::size_t>(radius + 1));
  for (int k = 0; k <= radius; ++k)
    w[static_cast<std::size_t>(k)] = phi[static_cast<std::size_t>(radius + k)] / sum;
  return w;
}

int extend_index(int i, int n, Extend mode) {
  if (i >= 0 && i < n) return i;
  if (mode == Extend::Nearest || n == 1) return i < 0 ? 0 : n - 1;
  const int period = 2 * n;
  int m = i % period;
  if (m < 0) m += period;
  return m < n ? m : period - 1 - m;
}

void gaussian_filter(cv::Mat& img, double sigma_y, double sigma_x, Extend mode, double truncate) {
  CV_Assert(img.depth() == CV_64F || img.depth() == CV_32F);
  const bool single = img.depth() == CV_32F;
  cv::Mat cur;
  img.convertTo(cur, CV_64F);
  if (sigma_y > 1e-15) {
    cv::Mat out(cur.size(), cur.type());
    correlate_rows(cur, out, gaussian_kernel(sigma_y, gaussian_radius(sigma_y, truncate)), mode);
    if (single) round_to_float(out);
    cur = out;
  }
  if (sigma_x > 1e-15) {
    cv::Mat out(cur.size(), cur.type());
    correlate_cols(cur, out, gaussian_kernel(sigma_x, gaussian_radius(sigma_x, truncate)), mode);
    cur = out;
  }
  cur.convertTo(img, img.type());  // float32: round to nearest, as ndimage's (float) cast
}

namespace {

// Axis 0 of gaussian_blur_u8 for one output row, as correlate_rows: the centre times w[0], then the
// pairs from the outermost in (the same operations per element, vectorised across the row).
FAULTLINE_CLONES("avx2")
void blur_rows_u8(double* out, const double* const* rows, const double* w, int r, std::size_t n) {
  const double* c = rows[r];
  for (std::size_t x = 0; x < n; ++x) out[x] = c[x] * w[0];
  for (int k = r; k >= 1; --k) {
    const double* a = rows[r - k];
    const double* b = rows[r + k];
    const double wk = w[k];
    for (std::size_t x = 0; x < n; ++x) out[x] += (a[x] + b[x]) * wk;
  }
}

// Axis 1 over an interleaved row of 3 channels padded by r pixels each side (`ext` points at the
// first real element), as correlate_line per channel, then clip * 255 truncated to uint8.
FAULTLINE_CLONES("avx2")
void blur_cols_u8(unsigned char* dst, const double* ext, double* acc, const double* w, int r,
                  std::size_t n) {
  for (std::size_t x = 0; x < n; ++x) acc[x] = ext[x] * w[0];
  for (int k = r; k >= 1; --k) {
    const double* a = ext - 3 * k;
    const double* b = ext + 3 * k;
    const double wk = w[k];
    for (std::size_t x = 0; x < n; ++x) acc[x] += (a[x] + b[x]) * wk;
  }
  for (std::size_t x = 0; x < n; ++x) {
    // clip(acc, 0, 1) * 255 truncated, clamped after the int32 conversion instead (the same bytes:
    // truncation goes toward zero), which lets the loop vectorise.
    std::int32_t v = static_cast<std::int32_t>(acc[x] * 255.0);
    v = v < 0 ? 0 : v;
    dst[x] = static_cast<unsigned char>(v > 255 ? 255 : v);
  }
}

}  // namespace

cv::Mat gaussian_blur_u8(const cv::Mat& bgr, double sigma) {
  CV_Assert(bgr.type() == CV_8UC3);
  const auto w = gaussian_kernel(sigma, gaussian_radius(sigma, 4.0));
  const int r = static_cast<int>(w.size()) - 1, rows = bgr.rows, cols = bgr.cols, width = cols * 3;
  const int slots = 2 * r + 1;
  const auto n = static_cast<std::size_t>(width);
  // Source row j (as u8 / 255 in float64) lives in slot j % slots while output rows i - r .. i + r
  // need it.
  std::vector<double> ring(static_cast<std::size_t>(slots) * n);
  auto slot = [&](int j) { return ring.data() + static_cast<std::size_t>(j % slots) * n; };
  int loaded = -1;
  // The axis-0 result with r edge pixels replicated on each side, and the axis-1 sums.
  std::vector<double> line(n + 6 * static_cast<std::size_t>(r)), acc(n);
  double* mid = line.data() + 3 * r;
  std::vector<const double*> taps(static_cast<std::size_t>(slots));
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int i = 0; i < rows; ++i) {
    for (; loaded < std::min(i + r, rows - 1); ++loaded) {
      const unsigned char* s = bgr.ptr<unsigned char>(loaded + 1);
      double* d = slot(loaded + 1);
      for (int x = 0; x < width; ++x) d[x] = s[x] / 255.0;
    }
    for (int k = -r; k <= r; ++k) {
      taps[static_cast<std::size_t>(k + r)] = slot(extend_index(i + k, rows, Extend::Nearest));
    }
    blur_rows_u8(mid, taps.data(), w.data(), r, n);
    for (int k = 1; k <= r; ++k) {
      for (int ch = 0; ch < 3; ++ch) {
        mid[-3 * k + ch] = mid[ch];
        mid[width - 3 + 3 * k + ch] = mid[width - 3 + ch];
      }
    }
    blur_cols_u8(out.ptr<unsigned char>(i), mid, acc.data(), w.data(), r, n);
  }
  return out;
}

namespace {

// Per output index along one axis: the interpolation start and the two weights of ndimage's order-1
// spline, or start = -1 where the coordinate falls outside [0, len - 1] (mode 'constant' then gives
// cval = 0).
struct LinearTap {
  int start = -1;
  int next = 0;  // index of the second tap (mirrored back inside at the last sample)
  double w0 = 0, w1 = 0;
};

std::vector<LinearTap> linear_taps(int in_len, int out_len) {
  const double zoom =
      out_len > 1 ? static_cast<double>(in_len - 1) / static_cast<double>(out_len - 1) : 1.0;
  std::vector<LinearTap> taps(static_cast<std::size_t>(out_len));
  for (int k = 0; k < out_len; ++k) {
    const double cc = static_cast<double>(k) * zoom;
    if (cc < 0 || cc > in_len - 1) continue;
    LinearTap& t = taps[static_cast<std::size_t>(k)];
    t.start = static_cast<int>(std::floor(cc));
    const double x = cc - std::floor(cc);
    t.w0 = 1.0 - x;
    t.w1 = 1.0 - t.w0;
    t.next =
        t.start + 1 < in_len ? t.start + 1 : (in_len > 1 ? in_len - 2 : 0);  // mirror extension
  }
  return taps;
}

}  // namespace

cv::Mat zoom_linear(const cv::Mat& img32, int out_rows, int out_cols) {
  CV_Assert(img32.type() == CV_32FC3);
  const auto ty = linear_taps(img32.rows, out_rows), tx = linear_taps(img32.cols, out_cols);
  cv::Mat out(out_rows, out_cols, CV_32FC3);
  for (int i = 0; i < out_rows; ++i) {
    const LinearTap& a = ty[static_cast<std::size_t>(i)];
    float* o = out.ptr<float>(i);
    if (a.start < 0) {
      for (int x = 0; x < out_cols * 3; ++x) o[x] = 0.f;
      continue;
    }
    const float* r0 = img32.ptr<float>(a.start);
    const float* r1 = img32.ptr<float>(a.next);
    for (int j = 0; j < out_cols; ++j) {
      const LinearTap& b = tx[static_cast<std::size_t>(j)];
      for (int c = 0; c < 3; ++c) {
        if (b.start < 0) {
          o[j * 3 + c] = 0.f;
          continue;
        }
        // The 2 x 2 x 2 footprint in C order; the channel axis's second tap has weight 0 and adds
        // +0.
        double t = 0.0;
        t += static_cast<double>(r0[b.start * 3 + c]) * a.w0 * b.w0;
        t += static_cast<double>(r0[b.next * 3 + c]) * a.w0 * b.w1;
        t += static_cast<double>(r1[b.start * 3 + c]) * a.w1 * b.w0;
        t += static_cast<double>(r1[b.next * 3 + c]) * a.w1 * b.w1;
        o[j * 3 + c] = static_cast<float>(t);
      }
    }
  }
  return out;
}

}  // namespace faultline::corruption::nd
