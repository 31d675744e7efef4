// The deterministic "digital" corruptions of imagecorruptions 1.1.2: contrast, saturate,
// gaussian_blur, pixelate and jpeg_compression. No randomness: numpy and fast mode give the same
// bytes except where noted (saturate and gaussian_blur have faster float32 paths in fast mode).
// Inputs are CV_8UC3 in the order the reference received them (BGR as RoboBEV feeds it; the
// reference treats channel 0 as red, which matters for saturate's hue sectors and JPEG's colour
// conversion, so it is kept as is).
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "common/status.hpp"

namespace faultline::corruption {

// contrast: (x - mean_c) * c + mean_c per channel, c = .4 .3 .2 .1 .05; the per-channel means of x
// = v / 255 are summed in float64 in memory order, as numpy's mean over axes (0, 1) of an HxWx3
// array does. Bit-exact.
cv::Mat contrast(const cv::Mat& bgr, int severity);
// The contrast factor c of severity 1..5 (clamped).
double contrast_factor(int severity);

// saturate: skimage rgb2hsv, S = clip(S * a + b, 0, 1), hsv2rgb; (a, b) = (0.3, 0) (0.1, 0) (2, 0)
// (5, 0.1) (20, 0.2). Mirrors the float path per pixel in double: bit-exact.
cv::Mat saturate(const cv::Mat& bgr, int severity);
struct SaturateParams {
  double scale;   // a
  double offset;  // b
};
// (a, b) of severity 1..5.
SaturateParams saturate_params(int severity);
// fast mode: the same map in closed form, c' = V - (V - c) * S' / S per channel, in float32
// (vectorisable). It rounds differently, so a truncated value may differ by one
// (tests/corruption/fast_ext_test.cpp bounds the share).
cv::Mat saturate_fast(const cv::Mat& bgr, int severity);

// Gaussian sigma of gaussian_blur by severity: 1 2 3 4 6 (pixels).
double gaussian_blur_sigma(int severity);
// gaussian_blur, numpy mode: skimage.filters.gaussian(multichannel) = scipy.ndimage.gaussian_filter
// with sigma (s, s, 0), mode 'nearest', truncate 4: rows then columns, scipy's symmetric float64
// correlation. Bit-exact.
cv::Mat gaussian_blur_exact(const cv::Mat& bgr, int severity);
namespace detail {
// The exact two-pass correlation with normalised weights w (2r + 1 values, symmetric), and the
// normalisation (division by numpy's pairwise sum) of unnormalised ones.
cv::Mat gaussian_blur_weights(const cv::Mat& bgr, const std::vector<double>& w);
std::vector<double> normalized_kernel(const std::vector<double>& phi);
}  // namespace detail

// fast mode: the fixed-point blur (fixed_point_blur.hpp: exact integer sums, truncated like the
// reference). Severities 1-2 (sigma 1, 2) blur at full resolution: within one level of the exact
// output on under 1 % of the values. From sigma 3 the same blur runs on the frame averaged in 2 x 2
// blocks (sigma 3, 4) or 4 x 4 blocks (sigma 6), with the sigma left after the blocks' and the
// bilinear upsampling's own variance (the frame first padded with the reference's 'nearest'
// border, to whole blocks), then bilinear back to full size: a few levels off at hard edges, PSNR
// > 50 dB and the mean within 0.3 of numpy mode on 1600x900 (tests/corruption/fast_ext_test.cpp).
cv::Mat gaussian_blur_fast(const cv::Mat& bgr, int severity);

// pixelate: PIL resize to (int(W * c), int(H * c)) with BOX (Pillow 9.4's fixed-point two-pass
// resampler), then back with NEAREST (Pillow's affine scale), c = .6 .5 .4 .3 .25. Bit-exact. Sizes
// below 1 pixel become 1 (the reference raises there).
cv::Mat pixelate(const cv::Mat& bgr, int severity);
// The downscale factor c of severity 1..5 (clamped).
double pixelate_factor(int severity);

// JPEG quality of jpeg_compression by severity: 25 18 15 10 7.
int jpeg_compression_quality(int severity);
// jpeg_compression: PIL's JPEG save (libjpeg-turbo, baseline, 4:2:0, standard tables scaled by
// quality, islow DCT) and decode (islow, fancy upsampling), through TurboJPEG with the same
// settings. Bit-exact. kInternal if TurboJPEG fails.
Result<cv::Mat> jpeg_compression(const cv::Mat& bgr, int severity);

}  // namespace faultline::corruption
