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

  // Columns [x0, x1) of output row y, upsampled from `grid` (CV_8UC3 of the grid size), into out[3
  // x0 .. 3 x1).
  void row(const cv::Mat& grid, int y, int x0, int x1, uchar* out);

 private:
  std::vector<int> col_,
      col_w_;  // per output column: left grid column and its neighbour's weight (of 256)
  std::vector<int> row_,
      row_w_;               // per output row: upper grid row and the lower one's weight (of 256)
  std::vector<int> blend_;  // one grid row blended vertically (x 256)
};

}  // namespace faultline::corruption
