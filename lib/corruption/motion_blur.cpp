// Motion blur as shifted multiply-adds over a horizontally edge-padded copy, one output row at a time.
#include "corruption/motion_blur.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
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

// Runs acc(row) = sum_i k_i * src(clamp(y - dy_i), clamp(x - dx_i)) for every row y and hands each finished
// accumulator row to `emit`. T is the source element type, A the accumulator type.
// With renormalise, the used taps are scaled to sum to 1 when the image is smaller than the streak.
template <typename T, typename A, typename Emit>
void run_taps(const cv::Mat& src, const double* kernel, const std::vector<TapOffset>& offsets, bool renormalise,
              Emit emit) {
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
  for (int i = 0; i < taps; ++i) pad = std::max(pad, std::abs(offsets[static_cast<std::size_t>(i)].dx));
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
    run_taps<std::uint8_t, A>(bgr, k->weights, offsets, renormalise, [&](int y, const A* acc, std::size_t n) {
      std::uint8_t* dst = out.ptr<std::uint8_t>(y);
      for (std::size_t j = 0; j < n; ++j) dst[j] = static_cast<std::uint8_t>(std::min(std::max(acc[j], 0.0), 255.0));
    });
  } else {
    // float32 sums sit within ~1e-4 of the exact double sum. Where a sum is that close to an integer n the pixel
    // is almost always in a flat region, whose exact result (n or n - 1, decided by the last ulps of the double
    // kernel) is tabulated here, so fast mode keeps flat regions identical to numpy mode.
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
    run_taps<std::uint8_t, A>(bgr, k->weights, offsets, renormalise, [&](int y, const A* acc, std::size_t n) {
      std::uint8_t* dst = out.ptr<std::uint8_t>(y);
      for (std::size_t j = 0; j < n; ++j) {
        const float v = std::min(std::max(acc[j], 0.0f), 255.0f);
        const float r = std::nearbyint(v);
        dst[j] = std::fabs(v - r) < 1e-3f ? flat[static_cast<int>(r)] : static_cast<std::uint8_t>(v);
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

cv::Mat blur_banded(const cv::Mat& bgr, int severity, double angle_deg, bool renormalise) {
  // float32 sums (8 lanes per AVX2 op, register-blocked) decide every value whose truncation is unambiguous; the
  // rest are recomputed with the exact float64 sum, so the output equals the float64 path bit for bit.
  const MotionBlurParams p = motion_blur_params(severity);
  const TabulatedKernel* k = find_tabulated_kernel(p.radius, p.sigma);
  const auto offsets = motion_offsets(angle_deg, k->width);
  const int rows = bgr.rows, cols = bgr.cols, ch = bgr.channels();
  const int taps = usable_taps(offsets, rows, cols);
  double used = 0.0;
  for (int i = 0; i < taps; ++i) used += k->weights[i];
  // Fast mode: images smaller than the streak renormalise the used taps (see the header).
  const bool scale = renormalise && taps < k->width && used > 0.0;
  std::vector<double> wd(static_cast<std::size_t>(taps));
  std::vector<float> wf(static_cast<std::size_t>(taps));
  for (int i = 0; i < taps; ++i) {
    wd[static_cast<std::size_t>(i)] = scale ? k->weights[i] / used : k->weights[i];
    wf[static_cast<std::size_t>(i)] = static_cast<float>(wd[static_cast<std::size_t>(i)]);
  }
  // |float32 sum - real sum| <= (2 * taps + 2) * 256 * 2^-24 (weight, product and addition roundings on values
  // <= 255 * sum(w)); the float64 reference is far closer. Outside this band both truncate to the same integer.
  const float band = static_cast<float>((2.0 * taps + 2.0) * 256.0 * 0x1p-24);
  int pad = 0;
  for (int i = 0; i < taps; ++i) pad = std::max(pad, std::abs(offsets[static_cast<std::size_t>(i)].dx));
  thread_local cv::Mat padded;  // reused per thread: a fresh 4 MB buffer per frame costs page faults
  cv::copyMakeBorder(bgr, padded, 0, 0, pad, pad, cv::BORDER_REPLICATE);
  cv::Mat out(bgr.size(), bgr.type());
  const std::size_t n = static_cast<std::size_t>(cols) * static_cast<std::size_t>(ch);
  std::vector<float> acc(n);
  std::vector<std::uint8_t> ambiguous(n);
  std::vector<const std::uint8_t*> src(static_cast<std::size_t>(taps));
  // The exact float64 result of a flat neighbourhood of value v (same summation order as the exact path).
  std::uint8_t flat[256];
  for (int v = 0; v < 256; ++v) {
    double sum = 0.0;
    for (int i = 0; i < taps; ++i) sum += wd[static_cast<std::size_t>(i)] * v;
    flat[v] = static_cast<std::uint8_t>(std::min(std::max(sum, 0.0), 255.0));
  }
  for (int y = 0; y < rows; ++y) {
    for (int i = 0; i < taps; ++i) {
      const auto& o = offsets[static_cast<std::size_t>(i)];
      const int sy = std::clamp(y - o.dy, 0, rows - 1);
      src[static_cast<std::size_t>(i)] = padded.ptr<std::uint8_t>(sy) + static_cast<std::ptrdiff_t>(pad - o.dx) * ch;
    }
    simd::weighted_rows(acc.data(), src.data(), wf.data(), taps, n);
    std::uint8_t* dst = out.ptr<std::uint8_t>(y);
    if (simd::truncate_outside_band(acc.data(), band, dst, ambiguous.data(), n) == 0) continue;
    for (std::size_t j = 0; j < n; ++j) {
      if (!ambiguous[j]) continue;
      // Flat neighbourhoods (all taps equal) land exactly on the band; their exact value is tabulated.
      const std::uint8_t first = src[0][j];
      int i = 1;
      while (i < taps && src[static_cast<std::size_t>(i)][j] == first) ++i;
      if (i == taps) {
        dst[j] = flat[first];
        continue;
      }
      double sum = 0.0;
      for (i = 0; i < taps; ++i) sum += wd[static_cast<std::size_t>(i)] * src[static_cast<std::size_t>(i)][j];
      dst[j] = static_cast<std::uint8_t>(std::min(std::max(sum, 0.0), 255.0));
    }
  }
  return out;
}

}  // namespace

cv::Mat motion_blur_fast(const cv::Mat& bgr, int severity, double angle_deg) {
  return blur_banded(bgr, severity, angle_deg, true);
}

cv::Mat motion_blur_numpy(const cv::Mat& bgr, int severity, double angle_deg) {
  return blur_banded(bgr, severity, angle_deg, false);
}

cv::Mat blur_layer(const cv::Mat& layer, int radius, int sigma, double angle_deg) {
  const TabulatedKernel* k = find_tabulated_kernel(radius, sigma);
  const auto offsets = motion_offsets(angle_deg, k->width);
  cv::Mat out(layer.size(), layer.type());
  if (layer.depth() == CV_64F) {
    run_taps<double, double>(layer, k->weights, offsets, false, [&](int y, const double* acc, std::size_t n) {
      std::copy(acc, acc + n, out.ptr<double>(y));
    });
  } else {
    // Fast layer: register-blocked float32 sums, same tap order and rounding as the streaming version.
    const int rows = layer.rows, cols = layer.cols;
    const int taps = usable_taps(offsets, rows, cols);
    double used = 0.0;
    for (int i = 0; i < taps; ++i) used += k->weights[i];
    const bool scale = taps < k->width && used > 0.0;
    std::vector<float> w(static_cast<std::size_t>(taps));
    int pad = 0;
    for (int i = 0; i < taps; ++i) {
      w[static_cast<std::size_t>(i)] = static_cast<float>(scale ? k->weights[i] / used : k->weights[i]);
      pad = std::max(pad, std::abs(offsets[static_cast<std::size_t>(i)].dx));
    }
    // Reused per thread: a fresh 6 MB buffer per frame costs more in page faults than the copy itself.
    thread_local cv::Mat padded;
    cv::copyMakeBorder(layer, padded, 0, 0, pad, pad, cv::BORDER_REPLICATE);
    std::vector<const float*> src(static_cast<std::size_t>(taps));
    for (int y = 0; y < rows; ++y) {
      for (int i = 0; i < taps; ++i) {
        const auto& o = offsets[static_cast<std::size_t>(i)];
        src[static_cast<std::size_t>(i)] = padded.ptr<float>(std::clamp(y - o.dy, 0, rows - 1)) + (pad - o.dx);
      }
      simd::weighted_rows(out.ptr<float>(y), src.data(), w.data(), taps, static_cast<std::size_t>(cols));
    }
  }
  return out;
}

}  // namespace faultline::corruption
