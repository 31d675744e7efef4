// Elastic Transform (imagecorruptions 1.1.2 `elastic_transform`): each pixel is resampled
// (bilinear, half-sample symmetric borders) at a displacement (dy, dx): uniform noise in +-0.005 H
// per pixel, Gaussian-smoothed with sigma (0.01 H, 0.01 W) (truncate 3, reflecting borders) and
// scaled by alpha = 250 x (0.05, 0.065, 0.085, 0.1, 0.12).
#pragma once

#include <opencv2/core.hpp>

#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

// alpha for severity 1..5.
double elastic_alpha(int severity);

// numpy mode: H x W uniforms for dx, then H x W for dy; scipy gaussian_filter and
// map_coordinates(order=1, mode='reflect') in float64 over the float32 image, as the reference;
// exact.
cv::Mat elastic_transform_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng);

// fast mode: the displacement field drawn and smoothed at a quarter of the resolution (scaled to
// the same variance) and interpolated up, then one OpenCV bilinear remap of the 8-bit image.
cv::Mat elastic_transform_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng);

// The displacement fields (CV_32F, H x W) of numpy mode, for tests and benchmarks.
void elastic_fields_numpy(int rows, int cols, int severity, rng::NumpyRandomState& rng, cv::Mat& dx,
                          cv::Mat& dy);

}  // namespace faultline::corruption
