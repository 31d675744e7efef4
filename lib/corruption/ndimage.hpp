// The few NumPy / SciPy ndimage / scikit-image numerics that imagecorruptions 1.1.2 builds its
// blurs from, mirrored operation for operation so numpy mode reproduces the reference bit for bit
// (NumPy 1.24 on an AVX-512 CPU, SciPy 1.10, scikit-image 0.19). Arrays are cv::Mat, H x W x C
// interleaved (the NumPy layout).
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>
#include <vector>

#include "common/pairwise_sum.hpp"

namespace faultline::corruption::nd {

// np.exp on float64 as NumPy 1.24 computes it on an AVX-512 CPU (its AVX512F table method after
// Tang, with FMA); it differs from glibc's exp by 1 ulp on some arguments, which moves truncated
// outputs.
double numpy_exp(double x);

// np.sum of a contiguous float64 vector (common/pairwise_sum.hpp).
using ::faultline::pairwise_sum;

// scipy.ndimage's order-0 Gaussian weights for offsets -radius..radius: exp(-0.5 / sigma^2 * x^2),
// normalised by their pairwise sum. radius = int(truncate * sigma + 0.5).
int gaussian_radius(double sigma, double truncate);
std::vector<double> gaussian_kernel(double sigma, int radius);

// Boundary extensions of scipy.ndimage: Nearest repeats the edge (aaa|abcd|ddd), Reflect is
// half-sample symmetric (cba|abcd|dcb), repeated for any distance.
enum class Extend { Nearest, Reflect };
int extend_index(int i, int n, Extend mode);

// scipy.ndimage.gaussian_filter on `img` (CV_64FC(n) or CV_32FC(n), filtered per channel, in
// place): axis 0 with sigma_y, then axis 1 with sigma_x (an axis with sigma <= 1e-15 is skipped),
// each pass in double and stored in the image's depth, as SciPy stores each pass in the output
// array. skimage.filters.gaussian with channel_axis=-1 is this with sigma_y = sigma_x (mode
// Nearest, truncate 4 by default).
void gaussian_filter(cv::Mat& img, double sigma_y, double sigma_x, Extend mode,
                     double truncate = 4.0);

// clip(skimage.filters.gaussian(u8 / 255, sigma, channel_axis=-1), 0, 1) * 255 truncated to uint8,
// for a CV_8UC3 image: the same arithmetic as gaussian_filter (Nearest, truncate 4) on the float64
// image, evaluated row by row without holding float64 images (the full-frame buffers cost more in
// page faults than the filter itself).
cv::Mat gaussian_blur_u8(const cv::Mat& bgr, double sigma);

// scipy.ndimage.zoom(img, (zy, zx, 1), order=1, mode='constant') of a CV_32FC3 image to out_rows x
// out_cols, with SciPy's corner-aligned coordinates (in - 1) / (out - 1): output CV_32FC3.
cv::Mat zoom_linear(const cv::Mat& img32, int out_rows, int out_cols);

// numpy's float -> uint8 conversion as x86 compiles it: through a 32-bit integer, keeping the low
// byte.
inline unsigned char to_u8_wrap(double v) {
  return static_cast<unsigned char>(static_cast<int>(v));
}

}  // namespace faultline::corruption::nd
