// Motion Blur (imagecorruptions 1.1.2 numpy version, spec corruptions.md §6): a one-sided Gaussian
// streak along an angle drawn as U(-45°, 45°). Deterministic given the angle. Edges replicate.
// Images smaller than the streak: the exact path keeps the reference's rule (taps stop at the first
// offset that reaches the image size, and the lost weight darkens the image: a 1x1 image is scaled
// by k_0 ~ 0.1-0.23). The fast path renormalises the used taps so that tiny images keep their
// brightness (a 1x1 image stays unchanged).
#pragma once

#include <opencv2/core.hpp>

namespace faultline::corruption {

struct MotionBlurParams {
  int radius;
  int sigma;
};
// Severity 1..5 -> (10,3), (15,5), (15,8), (15,12), (20,15).
MotionBlurParams motion_blur_params(int severity);

// Exact reference arithmetic (float64 accumulation, product rounded before the add, truncation).
// bgr: CV_8UC3.
cv::Mat motion_blur_exact(const cv::Mat& bgr, int severity, double angle_deg);

// numpy mode: float32 sums over half-precision rows, with the float64 sum (reference order)
// recomputed wherever the float32 value lies within its error bound of an integer. Bit-identical to
// motion_blur_exact (which stays as the plain float64 reference) and much faster.
cv::Mat motion_blur_numpy(const cv::Mat& bgr, int severity, double angle_deg);

// Fast mode: float32 sums over float32 rows, taps on the same pixel merged and a tail of weight
// <= 1.5e-6 left out; values within the error band of an integer take the exact flat result (all
// taps equal) or a float64 sum over the merged taps. Within 1 of numpy mode; it differs only where
// that float64 sum (another order) truncates differently from the reference's, which none of the
// measured frames showed. Images smaller than the streak renormalise the used taps. (float32 sums
// with the flat table alone are not enough: near-flat neighbourhoods, taps that differ only where
// the weight is ~1e-10, sit on an integer and came out 1 off in 0.3-1.2 % of the golden cases'
// values.)
cv::Mat motion_blur_fast(const cv::Mat& bgr, int severity, double angle_deg);

// Blurs a single-channel layer (CV_64F exact, CV_32F fast) with the tabulated (radius, sigma)
// kernel; output has the input's type and size. Used by Snow.
cv::Mat blur_layer(const cv::Mat& layer, int radius, int sigma, double angle_deg);

}  // namespace faultline::corruption
