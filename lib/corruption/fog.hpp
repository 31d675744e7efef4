// Fog (imagecorruptions `fog`, spec corruptions.md §4): a diamond-square plasma fractal added to
// every channel, then rescaled by m / (m + a) with m the image maximum. The fractal is N x N, N the
// smallest power of two
// >= max(H, W, 3), cropped top-left. All-black frames give pure fog (m = 0 -> black: the
// reference's formula multiplies by m, kept as is); all-white frames stay white where the fractal
// is 0 and darken elsewhere.
#pragma once

#include <opencv2/core.hpp>

#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

struct FogParams {
  double strength;  // a
  double decay;     // wibble decay d
};
// Severity 1..5 -> (1.5, 2), (2, 2), (2.5, 1.7), (2.5, 1.5), (3, 1.4).
FogParams fog_params(int severity);

// Smallest power of two >= max(rows, cols, 3).
int fog_map_size(int rows, int cols);

// The reference plasma fractal (float64, normalised to [0, 1] over the full map), CV_64F mapsize x
// mapsize. With NumpyRandomState it consumes exactly mapsize^2 - 1 uniforms, as the reference does.
cv::Mat plasma_fractal(int mapsize, double decay, rng::NumpyRandomState& rng);
cv::Mat plasma_fractal(int mapsize, double decay, rng::FastRng& rng);
// The same map's normalised top-left rows x cols crop, without materialising the normalised full
// map.
cv::Mat plasma_fractal_crop(int mapsize, double decay, rng::NumpyRandomState& rng, int rows,
                            int cols);

// Exact blend: out = trunc(clip((x + a*F) * m / (m + a), 0, 1) * 255), x = u8/255. fractal: CV_64F,
// values in [0, 1] (a normalised plasma map), at least as large as the image (top-left crop is
// used).
cv::Mat fog_blend_exact(const cv::Mat& bgr, const cv::Mat& fractal, double strength);

// numpy-mode fog in one call: the same draws and bytes as fog_blend_exact(bgr,
// plasma_fractal_crop(...)), without materialising the normalised crop (the blend reads the
// fractal's finest level directly). CV_8UC3 input.
cv::Mat fog_exact(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng);

// float32 blend of a CV_32F field of the image's size (values in [0, 1]).
cv::Mat fog_blend_fast(const cv::Mat& bgr, const cv::Mat& field, double strength);

// A fast-mode fog field for rows x cols (CV_32F): the plasma fractal at a quarter of the resolution
// (the finest two levels carry < 0.1 % of the amplitude), normalised over the full map, bilinearly
// upsampled (corner-aligned: low-resolution point i sits at full-resolution 4i, as in the full
// map). Only the crop's part of that map's finest level is computed and drawn (its extremes stay
// exact). The uniforms come from an rng::LaneRng seeded by one draw of rng (rng advances by exactly
// one draw per call).
cv::Mat fog_field_fast(int rows, int cols, double decay, rng::FastRng& rng);

// fast-mode fog in one call: the same field as fog_field_fast(...) (same draws), blended in 16-bit
// fixed point (8 fraction bits, fog_kernels.hpp) straight from the horizontally upsampled rows, the
// vertical lerp by rounding averages in registers. Within 1 of fog_blend_fast(bgr,
// fog_field_fast(...)) everywhere, and equal to it on all but ~0.1-0.5 % of values
// (FogFastTest.FusedIsWithinOneOfFieldThenBlendOnFewValues). Injected fields go through
// fog_blend_fast.
cv::Mat fog_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng);

// Upsamples a low-resolution toroidal map (CV_32F or CV_64F, values in [0, 1]) by `factor` and
// returns the rows x cols window whose top-left corner is at (row0, col0) in upsampled coordinates
// (wrapping). CV_32F.
cv::Mat upsample_torus_window(const cv::Mat& low, int factor, double row0, double col0, int rows,
                              int cols);

}  // namespace faultline::corruption
