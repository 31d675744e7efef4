// Glass Blur (imagecorruptions 1.1.2 `glass_blur`): Gaussian blur, then `iterations` passes over
// rows H-d down to d+1 and columns W-d down to d+1 (bottom-right first), each pixel taking the
// value of the pixel at a random offset (dx, dy) in [-d, d) (a copy, not a swap: the reference's
// tuple assignment of NumPy views writes only the first pixel), then blur again. The blurs are
// skimage.filters.gaussian (edge-replicating, truncate 4) of u8 / 255 in float64; the first is
// truncated to uint8. Images of at most 2d + 1 rows or columns skip the walk.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>

#include "rng/fast_rng.hpp"
#include "rng/lane_rng.hpp"
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

// fast mode: the same pixel walk with offsets from LaneRng lanes seeded by `rng` (one 32-bit value
// per pixel, a row at a time; the walk, one Python iteration per pixel, is what makes the reference
// take minutes), and the blurs in exact fixed point (fixed_point_blur.hpp), with the reference's
// truncation of flat areas.
cv::Mat glass_blur_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng);

namespace detail {
// fast mode's walk offsets for one row of `count` pixels: pixel k takes value k % 16 of LaneRng
// step k / 16 (whole steps, so `out` holds count rounded up to 16), dx from its low 16 bits and dy
// from its high 16, each (bits * 2 delta) >> 16 - delta, as the byte offset dy * row_step + 3 dx.
// allow_simd = false forces the portable body (tests: both give the same values).
void glass_row_offsets(std::int32_t* out, std::size_t count, rng::LaneRng& lanes, int delta,
                       std::int32_t row_step, bool allow_simd = true);
}  // namespace detail

}  // namespace faultline::corruption
