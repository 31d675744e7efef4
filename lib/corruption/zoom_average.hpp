// One step of zoom_blur's fast cascade in a single pass: the mean of a frame and of its centre crop
// scaled up to cover it, in 8-bit fixed-point arithmetic (no scaled layer is ever stored).
#pragma once

#include <opencv2/core.hpp>

namespace faultline::corruption {

// The layer is `crop` of `in` scaled to `scaled` with scipy.ndimage.zoom's order-1 geometry (output
// index k samples the crop at k (n_in - 1) / (n_out - 1), corner to corner), then trimmed to in's
// size from ((scaled - size) / 2) as the reference trims it. Each layer value is interpolated in
// 1/64 of a level: columns with weights in 1/64, then rows with weights in 2^-15 (rounded); then
// out = floor((64 in + layer_q6 + bias) / 128), bias in [0, 127] (32 is a mean rounded down on
// average by a quarter level, 96 one rounded up by as much). So a flat neighbourhood keeps its
// value. `in` is CV_8UC3, `scaled` at least in's size; `out` is (re)allocated and must not be
// `in`. The AVX2 and portable paths give the same bytes.
void zoom_average(const cv::Mat& in, const cv::Rect& crop, const cv::Size& scaled, int bias,
                  cv::Mat& out);

}  // namespace faultline::corruption
