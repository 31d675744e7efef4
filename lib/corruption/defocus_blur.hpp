// Defocus Blur (imagecorruptions 1.1.2 `defocus_blur`): each channel correlated with an
// anti-aliased disk (a binary disk of the severity's radius on a grid of at least 17 x 17,
// normalised, then smoothed by a 3 x 3 or 5 x 5 Gaussian). Deterministic. OpenCV does the
// reference's filtering (cv2.GaussianBlur, cv2.filter2D on float64, with reflect-101 borders), so
// calling it the same way reproduces the reference. Where the disk reaches the grid's edge
// (severities 4 and 5) that border folds its rim back in: the kernel sums to 1.013 / 1.011, and
// flat areas come out up to 2 levels brighter, as in the reference.
#pragma once

#include <opencv2/core.hpp>

namespace faultline::corruption {

struct DefocusParams {
  int radius;
  double alias_blur;  // sigma of the anti-aliasing Gaussian
};
// Severity 1..5 -> (3, 0.1), (4, 0.5), (6, 0.5), (8, 0.5), (10, 0.5).
DefocusParams defocus_params(int severity);

// The reference's disk kernel (CV_32F, 17 x 17 up to radius 8, else (2r + 1)^2).
cv::Mat defocus_kernel(int severity);

// numpy mode: float64 per channel, as the reference; exact.
cv::Mat defocus_blur_exact(const cv::Mat& bgr, int severity);

// fast mode: the disk's sums in exact integers, each row's from the one above (2 r + 1 pixels in
// and out per value), then the anti-aliasing Gaussian in float32, plus three taps per side for the
// rim the grid folds back in (severities 4, 5). Within 1 of numpy mode on < 1 % of
// values (tests/corruption/fast_mode_ext_spatial_test.cpp).
cv::Mat defocus_blur_fast(const cv::Mat& bgr, int severity);

}  // namespace faultline::corruption
