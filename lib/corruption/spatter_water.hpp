// fast mode's water for spatter (spatter.cpp): the 8-bit liquid from the field's draws, and the
// tint's strength from the liquid's edges, each a few streaming passes over rows.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "corruption/spatter.hpp"
#include "rng/fast_rng.hpp"

namespace faultline::corruption {

// The frame-sized buffers of the water, reused from frame to frame where the size repeats
// (spatter_fast keeps one per thread: a fresh 1.4 MB buffer costs its page faults every frame).
struct WaterScratch {
  cv::Mat liquid8, edges, distance, strength;
  std::vector<std::uint8_t> canny_map;
};

// s.liquid8 = uint8(field * 255) where the smoothed field >= p.threshold, else 0 (CV_8U, `size`):
// triangular draws with the normal's mean and variance, the Gaussian to 3 sigma (replicate
// border).
void water_liquid8(cv::Size size, const SpatterParams& p, rng::FastRng& rng, WaterScratch& s);

// s.strength (CV_8U, liquid8's size): what numpy mode computes with OpenCV from s.liquid8's Canny
// edges: the distance to them (exact Euclidean, capped at 20, in place of the 5 x 5 chamfer)
// through its 3 x 3 mean, equalizeHist, the emboss kernel and a 3 x 3 mean. Returns the largest
// liquid8 * strength.
int water_strength_fast(WaterScratch& s);

// Its last steps, in place: dist8 (CV_8U, values 0..20) = blur(filter2D(equalizeHist(dist8),
// emboss)) with the values OpenCV gives (8-bit, reflect-101 borders, the emboss kernel -2 -1 0 /
// -1 1 1 / 0 1 2). Returns the largest liquid8 * result (liquid8: CV_8U, the same size).
int equalize_emboss_blur(cv::Mat& dist8, const cv::Mat& liquid8);

}  // namespace faultline::corruption
