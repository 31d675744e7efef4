// Bilinear upsampling of a low-resolution CV_8UC3 grid one output row at a time, for the sensor
// faults that keep their layers at 1/4 or 1/8 resolution: no full-size temporary (whose page faults
// cost more than the arithmetic on a busy machine), and only the columns a caller needs. Same
// sample positions as cv::resize INTER_LINEAR.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace faultline::corruption {

class GridUpsampler {
 public:
  GridUpsampler(cv::Size grid, cv::Size full);

  // The grid (CV_8UC3 of the grid size) the next rows come from; call it again whenever the grid
  // or its contents change (rows are kept widened between calls of row()).
  void set_grid(const cv::Mat& grid);

  // Columns [x0, x1) of output row y into out[3 x0 .. 3 x1).
  void row(int y, int x0, int x1, uchar* out);

 private:
  // Grid row `grid_row` widened, evicting a row other than `keep` if it has to.
  const std::vector<int>& widened(int grid_row, int keep);

  std::vector<int> col_,
      col_w_;  // per output column: left grid column and its neighbour's weight (of 256)
  std::vector<int> row_,
      row_w_;  // per output row: upper grid row and the lower one's weight (of 256)
  cv::Mat grid_;
  // Two grid rows widened to every output column (x 256), and which rows they are.
  std::vector<int> wide_[2];
  int wide_row_[2] = {-1, -1};
};

}  // namespace faultline::corruption
