// Fixed-point bilinear taps (8-bit weights): grid rows widened once each, then one vertical blend
// per output row.
#include "corruption/grid_upsample.hpp"

#include <algorithm>
#include <cmath>

#include "common/simd.hpp"

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

// out[i] = (above[i] (256 - w) + below[i] w + 2^15) >> 16: the same integer as columns after rows.
FAULTLINE_CLONES("avx2")
void blend_rows(uchar* out, const int* above, const int* below, int w, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    out[i] = static_cast<uchar>((above[i] * (256 - w) + below[i] * w + 32768) >> 16);
}

}  // namespace

GridUpsampler::GridUpsampler(cv::Size grid, cv::Size full) {
  taps(grid.width, full.width, col_, col_w_);
  taps(grid.height, full.height, row_, row_w_);
  for (auto& w : wide_) w.resize(static_cast<std::size_t>(3 * full.width));
}

void GridUpsampler::set_grid(const cv::Mat& grid) {
  grid_ = grid;
  wide_row_[0] = wide_row_[1] = -1;
}

// Bilinear weights multiply out, so widening grid rows first (once per grid row, a quarter or an
// eighth of the output rows) gives the same integers as blending rows first for every output row.
const std::vector<int>& GridUpsampler::widened(int grid_row, int keep) {
  for (int s = 0; s < 2; ++s)
    if (wide_row_[s] == grid_row) return wide_[s];
  const int s = wide_row_[0] == keep ? 1 : 0;
  const uchar* g = grid_.ptr<uchar>(grid_row);
  std::vector<int>& w = wide_[s];
  for (std::size_t x = 0; x < col_.size(); ++x) {
    const int c0 = col_[x], wx = col_w_[x], c1 = std::min(c0 + 1, grid_.cols - 1);
    for (int c = 0; c < 3; ++c) w[3 * x + c] = g[3 * c0 + c] * (256 - wx) + g[3 * c1 + c] * wx;
  }
  wide_row_[s] = grid_row;
  return w;
}

void GridUpsampler::row(int y, int x0, int x1, uchar* out) {
  if (x0 >= x1) return;
  const int r0 = row_[static_cast<std::size_t>(y)], wy = row_w_[static_cast<std::size_t>(y)];
  const int r1 = std::min(r0 + 1, grid_.rows - 1);
  const int* above = widened(r0, r1).data();
  const int* below = widened(r1, r0).data();
  const auto from = static_cast<std::size_t>(3 * x0);
  blend_rows(out + from, above + from, below + from, wy, static_cast<std::size_t>(3 * (x1 - x0)));
}

}  // namespace faultline::corruption
