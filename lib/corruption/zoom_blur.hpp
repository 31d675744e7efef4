// Zoom Blur (imagecorruptions 1.1.2 `zoom_blur`): the mean of the image and of centre crops of it
// zoomed back up by each factor of the severity (np.arange(1, 1.11, 0.01) ... np.arange(1, 1.31,
// 0.03): 12 to 16 layers), in float32. Deterministic. The zoom is scipy.ndimage.zoom(order=1,
// mode='constant'): corner-aligned bilinear.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace faultline::corruption {

// The severity's zoom factors as np.arange produces them (start + i * (second - start)).
std::vector<double> zoom_blur_factors(int severity);

// numpy mode: exact.
cv::Mat zoom_blur_exact(const cv::Mat& bgr, int severity);

// fast mode: 16 layers from four cascaded zooms (A <- (A + zoom(A)) / 2 in one 8-bit pass each,
// zoom_average.hpp, the reference's crop geometry per factor), the four factors fitted so that the
// layers' log scales follow the reference's; an approximation: PSNR > 35 dB against numpy mode,
// mean within 0.25, values off by tens of levels at high-contrast edges far from the centre.
cv::Mat zoom_blur_fast(const cv::Mat& bgr, int severity);

}  // namespace faultline::corruption
