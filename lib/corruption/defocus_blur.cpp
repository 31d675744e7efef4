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

// fast mode's decomposition of the kernel: the binary disk (summed as vertical runs from column
// prefix sums, exact in integers) smoothed by the separable anti-aliasing Gaussian, plus the few
// taps where the reference's kernel differs from that (its 17 x 17 / 21 x 21 grid cuts the smoothed
// rim off and reflect-101 folds it back in at severities 4 and 5).
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
    for (const int along : {-spread, 0, spread}) {
      const float w = static_cast<float>(side.mass / (spread == 0 ? 1.0 : 3.0));
      if (spread == 0 && along != 0) continue;
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
void add_row(std::int32_t* next, const std::int32_t* prev, const std::uint8_t* row, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) next[i] = prev[i] + row[i];
}

FAULTLINE_CLONES("avx2")
void add_run(std::int32_t* acc, const std::int32_t* below, const std::int32_t* above,
             std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) acc[i] += below[i] - above[i];
}

// out[i] = sum_t w[t] * src[i + t * step] for t = 0..taps-1.
FAULTLINE_CLONES("avx2")
void smooth_int(float* out, const std::int32_t* src, const float* w, int taps, std::ptrdiff_t step,
                std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out[i] = w[0] * static_cast<float>(src[i]);
  for (int t = 1; t < taps; ++t) {
    const std::int32_t* s = src + t * step;
    for (std::size_t i = 0; i < n; ++i) out[i] += w[t] * static_cast<float>(s[i]);
  }
}

FAULTLINE_CLONES("avx2")
void axpy_rows(float* out, const float* const* rows, const float* w, int taps, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out[i] = w[0] * rows[0][i];
  for (int t = 1; t < taps; ++t) {
    for (std::size_t i = 0; i < n; ++i) out[i] += w[t] * rows[t][i];
  }
}

FAULTLINE_CLONES("avx2")
void axpy_u8(float* out, const std::uint8_t* src, float w, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out[i] += w * static_cast<float>(src[i]);
}

FAULTLINE_CLONES("avx2")
void store_truncated_f(std::uint8_t* dst, const float* src, float bias, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    // Clamped after the int32 conversion (truncation toward zero): no branches, so it vectorises.
    std::int32_t v = static_cast<std::int32_t>(src[i] + bias);
    v = v < 0 ? 0 : v;
    dst[i] = static_cast<std::uint8_t>(v > 255 ? 255 : v);
  }
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
  const auto padded_width = static_cast<std::size_t>(padded.cols) * 3;
  // Column prefix sums of the padded frame, row k = sum of padded rows < k, in a ring of the 2 half
  // + 2 rows one output row of disk sums reads.
  const int q_slots = 2 * plan.half + 2;
  std::vector<std::int32_t> q(static_cast<std::size_t>(q_slots) * padded_width, 0);
  auto q_row = [&](int k) {
    return q.data() + static_cast<std::size_t>(k % q_slots) * padded_width;
  };
  int q_done = 0;  // rows 0..q_done computed (row 0 is zeros)
  std::vector<std::int32_t> disk(ext_width);
  std::vector<float> h_ring(static_cast<std::size_t>(taps) * width), acc(width);
  std::vector<float> g(plan.g);
  std::vector<float> gh(plan.g);
  for (float& w : gh) w *= plan.inv_count;
  std::vector<const float*> v_rows(static_cast<std::size_t>(taps));
  cv::Mat out(bgr.size(), CV_8UC3);
  const int ext_rows = bgr.rows + 2 * s;
  for (int ye = 0; ye < ext_rows; ++ye) {
    for (; q_done < ye + 2 * plan.half + 1; ++q_done) {
      add_row(q_row(q_done + 1), q_row(q_done), padded.ptr<std::uint8_t>(q_done), padded_width);
    }
    // Disk sum at extended position (ye, xe), centred on padded (ye + half, xe + half): per column
    // dx the run of rows ye + half - run .. ye + half + run.
    std::fill(disk.begin(), disk.end(), 0);
    for (int dx = -plan.radius; dx <= plan.radius; ++dx) {
      const int run = plan.run[static_cast<std::size_t>(dx + plan.radius)];
      const std::size_t col = static_cast<std::size_t>(plan.half + dx) * 3;
      add_run(disk.data(), q_row(ye + plan.half + run + 1) + col, q_row(ye + plan.half - run) + col,
              ext_width);
    }
    float* h = h_ring.data() + static_cast<std::size_t>(ye % taps) * width;
    smooth_int(h, disk.data(), gh.data(), taps, 3, width);
    if (ye < 2 * s) continue;
    const int y = ye - 2 * s;
    for (int t = 0; t < taps; ++t) {
      v_rows[static_cast<std::size_t>(t)] =
          h_ring.data() + static_cast<std::size_t>((y + t) % taps) * width;
    }
    axpy_rows(acc.data(), v_rows.data(), g.data(), taps, width);
    for (const DiskPlan::Tap& tap : plan.residual) {
      axpy_u8(
          acc.data(),
          padded.ptr<std::uint8_t>(y + pad + tap.dy) + static_cast<std::size_t>(pad + tap.dx) * 3,
          tap.w, width);
    }
    store_truncated_f(out.ptr<std::uint8_t>(y), acc.data(), plan.bias, width);
  }
  return out;
}

}  // namespace faultline::corruption
