// Glass Blur (imagecorruptions 1.1.2 `glass_blur`): Gaussian blur, then `iterations` passes over
// rows H-d down to d+1 and columns W-d down to d+1 (bottom-right first), each pixel taking the
// value of the pixel at a random offset (dx, dy) in [-d, d) (a copy, not a swap: the reference's
// tuple assignment of NumPy views writes only the first pixel), then blur again. The blurs are
// skimage.filters.gaussian (edge-replicating, truncate 4) of u8 / 255 in float64; the first is
// truncated to uint8. Images of at most 2d + 1 rows or columns skip the walk.
#pragma once

#include <opencv2/core.hpp>

#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

struct GlassParams {
  double sigma;
  int delta;
  int iterations;
};
// Severity 1..5 -> (0.7, 1, 2), (0.9, 2, 1), (1, 2, 3), (1.1, 3, 2), (1.5, 4, 2).
GlassParams glass_params(int severity);

// numpy mode: draws randint(-d, d, size=2) (dx, then dy) per visited pixel; exact.
cv::Mat glass_blur_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng);

// fast mode: the same pixel walk with FastRng offsets (four per 64-bit draw; the walk, one Python
// iteration per pixel, is what makes the reference take minutes; drawn a row at a time), and the
// blurs in exact fixed point (fixed_point_blur.hpp), with the reference's truncation of flat areas.
cv::Mat glass_blur_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng);

}  // namespace faultline::corruption
