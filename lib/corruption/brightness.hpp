// Bright (imagecorruptions `brightness`, spec corruptions.md §2): V += c in scikit-image HSV, c =
// 0.1..0.5. Deterministic. Black becomes grey trunc(255c); white stays white; all-black frames
// become uniform grey.
#pragma once

#include <opencv2/core.hpp>

namespace faultline::corruption {

// Brightness offset c for severity 1..5.
double brightness_offset(int severity);

// Mirrors skimage's rgb2hsv/hsv2rgb float path per pixel in double, in stored (BGR) order:
// bit-exact. CV_8UC3.
cv::Mat brightness_exact(const cv::Mat& bgr, int severity);

// Same output, faster: per-severity tables (built on first use, thread-safe; < 1 MB and ~20 ms
// each) hold each channel's output by its role (max, min or middle) and the pixel max, and the HSV
// path's own results for middle channels whose closed form a * V2 / V lies within 1e-6 of a
// truncation boundary. Bit-identical to brightness_exact.
cv::Mat brightness_fast(const cv::Mat& bgr, int severity);

}  // namespace faultline::corruption
