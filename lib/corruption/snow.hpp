// Snow (imagecorruptions `snow`, numpy version, spec corruptions.md §5): a thresholded, zoomed
// normal field, motion-blurred along U(-135°, -45°), added twice (once rotated 180°) over a
// whitened image. The grey weights act on the stored channel order, i.e. 0.299*B + 0.587*G +
// 0.114*R for OpenCV images, as in nuScenes-C. Tiny images: the centre crop is at least 1x1 and a
// 1-pixel axis zooms by replication; the blur follows the motion-blur rules (motion_blur.hpp).
#pragma once

#include <opencv2/core.hpp>

#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

struct SnowParams {
  double loc, scale;  // normal field
  double zoom;
  double threshold;
  int radius, sigma;  // layer blur kernel
  double blend;       // b
};
SnowParams snow_params(int severity);

// Zoomed layer size for an image of rows x cols: round(ceil(n / z) * z) per axis (Python
// round-half-even).
cv::Size snow_layer_size(int rows, int cols, double zoom);

// Bit-exact reference: H*W normals then one uniform from `rng`.
cv::Mat snow_exact(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng);

// Deterministic stages, exposed so a test can inject the random field: `normals` is the H x W
// CV_64F field N(loc, scale); returns the uint8 snow layer (after blur and round-half-even),
// cropped to H x W.
cv::Mat snow_layer_exact(const cv::Mat& normals, int severity, double blur_angle_deg);
// Exact whitening and blend of a CV_8U layer (values / 255) into the image.
cv::Mat snow_blend_exact(const cv::Mat& bgr, const cv::Mat& layer_u8, int severity);

// Fast mode: normals only where the centre crop reads them (lock-step lanes seeded by one draw of
// `rng`, which also serves ziggurat rejections and the angle), float32 zoom, 16-bit fixed-point
// blur and blend (each within 1 level of its float32 form, so injected-field outputs are close to
// numpy mode's but not bit-exact; see snow_kernels.hpp).
cv::Mat snow_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng);
// Fast layer from a crop-sized CV_32F field (rows x cols is the image size).
cv::Mat snow_layer_fast(const cv::Mat& crop_field, int rows, int cols, int severity,
                        double blur_angle_deg);
cv::Mat snow_blend_fast(const cv::Mat& bgr, const cv::Mat& layer_u8, int severity);
// Same with the second, 180°-rotated copy given explicitly (so a moving layer can move both copies
// together).
cv::Mat snow_blend_fast(const cv::Mat& bgr, const cv::Mat& layer_u8, const cv::Mat& layer_rot_u8,
                        int severity);

}  // namespace faultline::corruption
