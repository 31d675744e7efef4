// fast mode's water for spatter (spatter.cpp): the 8-bit liquid from the field's draws, and the
// tint's strength from the liquid's edges, each a few streaming passes over rows.
#pragma once

#include <opencv2/core.hpp>

#include "corruption/spatter.hpp"
#include "rng/fast_rng.hpp"

namespace faultline::corruption {

// liquid8 = uint8(field * 255) where the smoothed field >= p.threshold, else 0 (CV_8U, `size`):
// triangular draws with the normal's mean and variance, the Gaussian to 3 sigma (replicate border).
cv::Mat water_liquid8(cv::Size size, const SpatterParams& p, rng::FastRng& rng);

// The strength (CV_8U, liquid8's size) numpy mode computes with OpenCV from liquid8's Canny
// edges: the distance to them (exact Euclidean, capped at 20, in place of the 5 x 5 chamfer)
// through its 3 x 3 mean, equalizeHist, the emboss kernel and a 3 x 3 mean; max_product = the
// largest liquid8 * strength.
cv::Mat water_strength_fast(const cv::Mat& liquid8, int& max_product);

}  // namespace faultline::corruption
