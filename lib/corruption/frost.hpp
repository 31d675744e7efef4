// Frost (imagecorruptions 1.1.2 `frost`): a frost texture, rescaled to cover the frame, cropped at
// a random offset and blended: clip(a * image + b * texture, 0, 255). The texture's channels are
// reversed before the blend, as the reference does (it reads the texture as BGR and flips it to RGB
// while the image it receives is BGR). The five textures the reference draws from (randint(5): its
// sixth is never used) are compiled in (frost_textures/, Apache-2.0, see NOTICE there); a caller
// may pass other textures instead.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::corruption {

struct FrostParams {
  double image_weight;    // a
  double texture_weight;  // b
};
// Severity 1..5 -> (1, 0.4), (0.8, 0.6), (0.7, 0.7), (0.65, 0.7), (0.6, 0.75).
FrostParams frost_params(int severity);

// The built-in textures frost1..frost5 (CV_8UC3 BGR, decoded once; thread-safe).
const std::vector<cv::Mat>& builtin_frost_textures();

// The reference's rescale of a texture for a rows x cols frame: by 1.1 x the factor that makes it
// cover the frame (1 if it already does), bicubic (OpenCV INTER_CUBIC).
cv::Mat frost_rescale(const cv::Mat& texture, int rows, int cols);

// numpy mode: randint(len) picks the texture, then randint for the crop row and column, as the
// reference draws them (with 5 textures: bit-exact). `textures` empty = the built-in ones.
cv::Mat frost_numpy(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng,
                    const std::vector<cv::Mat>& textures = {});

// fast mode: the same blend; the rescaled textures are cached per frame size (a few MB each).
cv::Mat frost_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng,
                   const std::vector<cv::Mat>& textures = {});

// The blend of a rescaled texture cropped at (y0, x0): clip(a * image + b * flipped texture),
// truncated to uint8.
cv::Mat frost_blend(const cv::Mat& bgr, const cv::Mat& rescaled, int y0, int x0, int severity);

}  // namespace faultline::corruption
