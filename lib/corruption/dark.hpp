// Dark / Low Light (RoboBEV LowLight, spec corruptions.md §3): gamma-2 contrast stretch of the
// whole image into [0, c], Poisson shot noise with scale P, Gaussian read noise sigma, truncation.
// Behaviour where the reference fails, defined here:
// - Severity 5 (IndexError in the reference): extrapolates the tables one step, c = 0.10, P = 15,
// sigma = 0.054.
// - Constant image (hi == lo, NaN in the reference): the stretch is taken as 0, so the output is
// pure read noise
//   trunc(255 * max(0, N(0, sigma))) (the same as the reference's pixels at the image minimum).
// All-black and all-white frames are constant images.
#pragma once

#include <opencv2/core.hpp>

#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

struct DarkParams {
  double target_max;     // c
  double poisson_scale;  // P
  double sigma;
};
// The reference indexes its lists with [severity]: severity s uses table entry s + 1 (s = 1..4); 5
// extrapolates.
DarkParams dark_params(int severity);

// lambda per input value v (0..255): ((v/255 - lo)/(hi - lo))^2 * c * 255 / 255 * P, the
// reference's arithmetic.
void dark_lambdas(const cv::Mat& bgr, int severity, double lambdas[256]);
// The same for an image whose minimum and maximum byte are lo_u8 and hi_u8.
void dark_lambdas(int lo_u8, int hi_u8, int severity, double lambdas[256]);

// Bit-exact: H*W*3 Poissons then H*W*3 normals, in B,G,R memory order (dark_exact.cpp).
cv::Mat dark_exact(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng);

// Fast mode: per input value a sampling table of the output value (Poisson and read noise folded
// into one discrete distribution), one table lookup per element with one 32-bit value from
// lock-step xoshiro lanes seeded by one draw of `rng` (AVX2 where available; the same bytes on
// every CPU for a seed).
cv::Mat dark_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng);

}  // namespace faultline::corruption
