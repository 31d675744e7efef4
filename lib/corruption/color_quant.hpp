// Color Quant (RoboBEV ColorQuant = PIL posterize, spec corruptions.md §7): keep 5 - severity bits
// per channel. Deterministic; severity 5 keeps no bits (all-black output).
#pragma once

#include <opencv2/core.hpp>

namespace faultline::corruption {

// AND mask per channel: 0xF0, 0xE0, 0xC0, 0x80, 0x00 for severity 1..5.
int color_quant_mask(int severity);

// Any 8-bit image; shape and channel count are kept.
cv::Mat color_quant(const cv::Mat& img, int severity);

}  // namespace faultline::corruption
