// Motion-blur geometry shared by Motion Blur and Snow: the tabulated one-sided Gaussian kernels and
// the integer tap offsets along a direction (spec corruptions.md §6).
#pragma once

#include <vector>

namespace faultline::corruption {

// Kernel weights k_0..k_{width-1} exactly as NumPy computed them for the reference (golden
// kernels.json).
struct TabulatedKernel {
  int radius;
  int sigma;
  const double* weights;
  int width;  // 2 * radius + 1
};

// Returns the table for (radius, sigma), or nullptr if the reference never uses that pair.
const TabulatedKernel* find_tabulated_kernel(int radius, int sigma);

struct TapOffset {
  int dy;
  int dx;
};

// Offsets (dy_i, dx_i) = (-ceil(i*P0/h - 0.5), -ceil(i*P1/h - 0.5)) for i = 0..width-1, P =
// width*(sin, cos)(angle).
std::vector<TapOffset> motion_offsets(double angle_deg, int width);

// Number of leading taps the reference applies on a rows x cols array: it stops at the first tap
// whose |dy| >= rows or |dx| >= cols.
int usable_taps(const std::vector<TapOffset>& offsets, int rows, int cols);

}  // namespace faultline::corruption
