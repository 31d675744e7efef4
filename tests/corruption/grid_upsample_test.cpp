// The grid upsampler: every row and span equals the documented integer bilinear (rows blended, then
// columns, 8-bit weights at cv::resize's sample positions), and a new grid is seen after set_grid.
#include "corruption/grid_upsample.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace faultline::corruption {
namespace {

// Source index and the next one's weight (of 256) for output i.
void tap(int n_src, int n_dst, int i, int& i0, int& w) {
  const double s = std::max(0.0, (i + 0.5) * n_src / n_dst - 0.5);
  i0 = static_cast<int>(s);
  w = static_cast<int>(std::lround((s - i0) * 256));
  if (i0 >= n_src - 1) i0 = n_src - 1, w = 0;
}

std::uint8_t restated(const cv::Mat& grid, cv::Size full, int y, int x, int c) {
  int r0, wy, c0, wx;
  tap(grid.rows, full.height, y, r0, wy);
  tap(grid.cols, full.width, x, c0, wx);
  const int r1 = std::min(r0 + 1, grid.rows - 1), c1 = std::min(c0 + 1, grid.cols - 1);
  auto blend = [&](int col) {
    return grid.at<cv::Vec3b>(r0, col)[c] * (256 - wy) + grid.at<cv::Vec3b>(r1, col)[c] * wy;
  };
  return static_cast<std::uint8_t>((blend(c0) * (256 - wx) + blend(c1) * wx + 32768) >> 16);
}

cv::Mat random_grid(cv::Size size, int seed) {
  cv::Mat g(size, CV_8UC3);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  rng.fill(g, cv::RNG::UNIFORM, 0, 256);
  return g;
}

TEST(GridUpsamplerTest, RowsAndSpansEqualTheIntegerBilinear) {
  for (const auto& [grid_size, full] :
       {std::pair{cv::Size(400, 225), cv::Size(1600, 900)},
        std::pair{cv::Size(7, 5), cv::Size(53, 37)}, std::pair{cv::Size(1, 1), cv::Size(9, 4)}}) {
    const cv::Mat grid = random_grid(grid_size, grid_size.width);
    GridUpsampler up(grid_size, full);
    up.set_grid(grid);
    std::vector<std::uint8_t> row(static_cast<std::size_t>(3 * full.width));
    // Rows in order, then a span of every row backwards (the kept rows must not go stale).
    for (int pass = 0; pass < 2; ++pass) {
      for (int k = 0; k < full.height; ++k) {
        const int y = pass == 0 ? k : full.height - 1 - k;
        const int x0 = pass == 0 ? 0 : full.width / 3, x1 = pass == 0 ? full.width : full.width - 1;
        up.row(y, x0, x1, row.data());
        for (int x = x0; x < x1; ++x) {
          for (int c = 0; c < 3; ++c) {
            ASSERT_EQ(row[static_cast<std::size_t>(3 * x + c)], restated(grid, full, y, x, c))
                << full << " y " << y << " x " << x << " c " << c;
          }
        }
      }
    }
  }
}

TEST(GridUpsamplerTest, SeesANewGridAfterSetGrid) {
  const cv::Size grid_size(10, 6), full(40, 24);
  cv::Mat grid = random_grid(grid_size, 1);
  GridUpsampler up(grid_size, full);
  std::vector<std::uint8_t> row(static_cast<std::size_t>(3 * full.width));
  up.set_grid(grid);
  up.row(5, 0, full.width, row.data());
  random_grid(grid_size, 2).copyTo(grid);  // same buffer, new contents
  up.set_grid(grid);
  up.row(5, 0, full.width, row.data());
  for (int x = 0; x < full.width; ++x) {
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(row[static_cast<std::size_t>(3 * x + c)], restated(grid, full, 5, x, c)) << x;
  }
}

}  // namespace
}  // namespace faultline::corruption
