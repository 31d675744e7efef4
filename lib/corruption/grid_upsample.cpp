// Fixed-point bilinear taps (8-bit weights), vertical pass per output row into a grid-width buffer,
// then horizontal.
#include "corruption/grid_upsample.hpp"

#include <algorithm>
#include <cmath>

namespace faultline::corruption {
namespace {

// Output index -> (source index, weight of source index + 1 in 1/256), half-pixel centres, clamped
// at the borders.
void taps(int n_src, int n_dst, std::vector<int>& index, std::vector<int>& weight) {
  index.resize(static_cast<std::size_t>(n_dst));
  weight.resize(static_cast<std::size_t>(n_dst));
  const double scale = static_cast<double>(n_src) / n_dst;
  for (int i = 0; i < n_dst; ++i) {
    const double s = std::max(0.0, (i + 0.5) * scale - 0.5);
    int i0 = static_cast<int>(s);
    int w = static_cast<int>(std::lround((s - i0) * 256));
    if (i0 >= n_src - 1) i0 = n_src - 1, w = 0;
    index[static_cast<std::size_t>(i)] = i0;
    weight[static_cast<std::size_t>(i)] = w;
  }
}

}  // namespace

GridUpsampler::GridUpsampler(cv::Size grid, cv::Size full) {
  taps(grid.width, full.width, col_, col_w_);
  taps(grid.height, full.height, row_, row_w_);
  blend_.resize(static_cast<std::size_t>(3 * grid.width));
}

void GridUpsampler::row(const cv::Mat& grid, int y, int x0, int x1, uchar* out) {
  if (x0 >= x1) return;
  const int r0 = row_[static_cast<std::size_t>(y)], wy = row_w_[static_cast<std::size_t>(y)];
  const int r1 = std::min(r0 + 1, grid.rows - 1);
  const uchar* a = grid.ptr<uchar>(r0);
  const uchar* b = grid.ptr<uchar>(r1);
  // Only the grid columns the output span reads.
  const int g0 = col_[static_cast<std::size_t>(x0)];
  const int g1 = std::min(grid.cols - 1, col_[static_cast<std::size_t>(x1 - 1)] + 1);
  for (int i = 3 * g0; i < 3 * (g1 + 1); ++i)
    blend_[static_cast<std::size_t>(i)] = a[i] * (256 - wy) + b[i] * wy;
  for (int x = x0; x < x1; ++x) {
    const int c0 = col_[static_cast<std::size_t>(x)], wx = col_w_[static_cast<std::size_t>(x)];
    const int c1 = std::min(c0 + 1, grid.cols - 1);
    for (int c = 0; c < 3; ++c) {
      const int v = blend_[static_cast<std::size_t>(3 * c0 + c)] * (256 - wx) +
                    blend_[static_cast<std::size_t>(3 * c1 + c)] * wx;
      out[3 * x + c] = static_cast<uchar>((v + 32768) >> 16);
    }
  }
}

}  // namespace faultline::corruption
