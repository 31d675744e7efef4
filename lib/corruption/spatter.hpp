// Spatter (imagecorruptions 1.1.2 `spatter`): a Gaussian-smoothed normal field thresholded into
// liquid. Severities 1-3: water, whose edges (Canny, distance transform, histogram equalisation, an
// emboss kernel) tint the image pale turquoise additively. Severities 4-5: mud, a blurred mask
// (kept where >= 0.8) that replaces the image by brown. The reference's colours are applied to the
// BGR array as if it were RGB (its quirk, kept: the water is (175, 238, 238) and the mud (63, 42,
// 20) in B, G, R order). Where the water branch finds no liquid at all, the reference divides 0 by
// 0 and returns a black frame; here the frame is returned unchanged instead (a defined behaviour
// for tiny or constant inputs).
#pragma once

#include <opencv2/core.hpp>

#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

struct SpatterParams {
  double loc, scale;  // normal field
  double sigma;       // its smoothing
  double threshold;   // liquid where the smoothed field >= this
  double intensity;   // water: scale of the tint; mud: sigma of the mask blur
  bool mud;
};
// Severity 1..5 -> (0.65, 0.3, 4, 0.69, 0.6, water), (0.65, 0.3, 3, 0.68, 0.6, water), (0.65, 0.3,
// 2, 0.68, 0.5, water), (0.65, 0.3, 1, 0.65, 1.5, mud), (0.67, 0.4, 1, 0.65, 1.5, mud).
SpatterParams spatter_params(int severity);

// numpy mode: H x W legacy normals, skimage/SciPy smoothing in float64; the OpenCV steps as the
// reference calls them.
cv::Mat spatter_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng);

// fast mode: the field smoothed in float32 with the Gaussian to 3 sigma. Mud (spatter_mud.hpp):
// Box-Muller normals, the field's Gaussian and threshold, the mask's Gaussian in integers and the
// blend, streamed by rows. Water (spatter_water.hpp):
// triangular draws (same mean and variance; the smoothed field's excess kurtosis within 0.025 of
// normal's 0) smoothed a row at a time straight into the 8-bit liquid, then numpy mode's steps with
// the same values, OpenCV's Canny computed by canny_l1 (edge_canny.hpp), except the distance to
// the edges, exact (Euclidean, capped at 20: a column sweep and a 41-tap row minimum) where the
// reference's 5 x 5 chamfer approximates it, and the blend, which adds trunc(k colour) per channel
// (one level below numpy's where its float sum rounds up); statistical tolerance as before
// (tests/corruption/fast_mode_ext_spatial_test.cpp). The water keeps its frame-sized buffers per
// thread (~7 MB at 1600 x 900).
cv::Mat spatter_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng);

// The stages after the smoothing, given the smoothed liquid field (CV_64F, H x W): shared by both
// modes.
cv::Mat spatter_apply(const cv::Mat& bgr, const cv::Mat& liquid, int severity, bool exact_blur);

}  // namespace faultline::corruption
