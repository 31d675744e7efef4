// The pointwise noise corruptions of imagecorruptions 1.1.2 (gaussian_noise, shot_noise,
// impulse_noise, speckle_noise) and RoboBEV's ISONoise. Each output byte depends only on its input
// byte and its own draws, so fast mode samples each byte's exact output distribution from a
// per-level table (one lookup per byte). Behaviour the reference does not define, defined here
// (docs/faults.md):
// - iso_noise severity 5 (IndexError in the reference): Gaussian sigma 0.7 * 0.54, the list's next
// step
//   (differences 0.04, 0.06, 0.08, 0.12 -> 0.16), Poisson scale 25 as at every severity.
// - impulse_noise cannot be seeded in the reference (skimage draws from
// np.random.default_rng(None)): numpy mode
//   runs skimage's algorithm (H*W*3 uniforms for "flipped", then H*W*3 for "salted") on the seeded
//   legacy stream.
#pragma once

#include <opencv2/core.hpp>

#include "corruption/types.hpp"
#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

// Whether `c` is one of the five noise corruptions of this file.
bool is_pointwise_noise(Corruption c);

// Constants by severity 1..5.
double gaussian_noise_sigma(int severity);  // .08 .12 .18 .26 .38
double shot_noise_scale(int severity);      // photons per unit: 60 25 12 5 3
double impulse_noise_amount(int severity);  // share of values replaced: .03 .06 .09 .17 .27
double speckle_noise_sigma(int severity);   // .15 .2 .35 .45 .6
double iso_noise_sigma(
    int severity);  // 0.7 * (.12 .18 .26 .38 .54): the reference's [severity] indexing

// numpy mode: bit-exact with the reference after np.random.seed (impulse_noise: see above), with
// its draws. Requires a continuous or non-continuous CV_8UC3 image and severity 1..5.
cv::Mat pointwise_noise_numpy(const cv::Mat& bgr, Corruption c, int severity,
                              rng::NumpyRandomState& rng);

// fast mode: each byte drawn from the reference's output distribution for its input value (alias
// tables built on first use per corruption and severity, thread-safe, 256 KB each), one 32-bit
// value per byte from lock-step xoshiro lanes seeded by one draw of `rng`.
cv::Mat pointwise_noise_fast(const cv::Mat& bgr, Corruption c, int severity, rng::FastRng& rng);

// The output distribution of one byte of input value v (0..255): prob[0..256), summing to 1
// (tests).
void pointwise_noise_distribution(Corruption c, int severity, int v, double prob[256]);

}  // namespace faultline::corruption
