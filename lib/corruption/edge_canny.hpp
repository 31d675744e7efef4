// Canny edges of an 8-bit image, equal to OpenCV's cv::Canny(src, edges, low, high) with the 3 x 3
// Sobel and the L1 gradient, at a fraction of its cost on liquid fields with many edge pixels
// (spatter's fast water): the Sobel, magnitude and non-maximum suppression row by row in
// vectorisable integer arithmetic, then the hysteresis over a flat index stack.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace faultline::corruption {

// CV_8U in, CV_8U out (255 on edges, 0 elsewhere), the same size; low <= high, both integers.
// `allow_simd` = false forces the portable body (tests; both give the same edges).
cv::Mat canny_l1(const cv::Mat& src, int low, int high, bool allow_simd = true);

// The same into `edges` (reallocated only where its size or type differs), with `map` as scratch
// ((rows + 2) x (cols + 2) bytes): callers that run frame after frame reuse both.
void canny_l1(const cv::Mat& src, int low, int high, cv::Mat& edges, std::vector<std::uint8_t>& map,
              bool allow_simd = true);

}  // namespace faultline::corruption
