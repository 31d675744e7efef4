// Dispatch from (type, severity, mode) to the corruption stages.
#include "corruption/corrupt.hpp"

#include <cmath>
#include <string>

#include "corruption/brightness.hpp"
#include "corruption/color_quant.hpp"
#include "corruption/dark.hpp"
#include "corruption/defocus_blur.hpp"
#include "corruption/digital.hpp"
#include "corruption/elastic_transform.hpp"
#include "corruption/fog.hpp"
#include "corruption/frost.hpp"
#include "corruption/glass_blur.hpp"
#include "corruption/motion_blur.hpp"
#include "corruption/noise.hpp"
#include "corruption/recompression.hpp"
#include "corruption/rolling_shutter.hpp"
#include "corruption/sensor_fault.hpp"
#include "corruption/snow.hpp"
#include "corruption/spatter.hpp"
#include "corruption/transport_corruption.hpp"
#include "corruption/zoom_blur.hpp"

namespace faultline::corruption {

Status validate_input(const cv::Mat& bgr, int severity) {
  if (bgr.empty()) return {StatusCode::kInvalidArgument, "empty image"};
  if (bgr.type() != CV_8UC3) {
    return {StatusCode::kUnsupported, "image type must be 8-bit 3-channel (CV_8UC3), got " +
                                          std::to_string(bgr.channels()) + " channel(s) of depth " +
                                          std::to_string(bgr.depth())};
  }
  return validate_severity(severity);
}

namespace {

// An injected angle must be a number: the tap geometry of a NaN or infinite angle is undefined.
Status validate_options(const CorruptOptions& options) {
  if (options.frost_textures) {
    if (options.frost_textures->empty())
      return {StatusCode::kInvalidArgument, "frost textures: the list is empty"};
    for (std::size_t i = 0; i < options.frost_textures->size(); ++i) {
      const cv::Mat& t = (*options.frost_textures)[i];
      if (t.empty() || t.type() != CV_8UC3) {
        return {StatusCode::kInvalidArgument,
                "frost texture " + std::to_string(i) +
                    ": expected a non-empty 8-bit 3-channel (BGR) image"};
      }
    }
  }
  if (options.yaw_rate_rad_s && !std::isfinite(*options.yaw_rate_rad_s)) {
    return {StatusCode::kInvalidArgument,
            "rolling shutter yaw rate must be a finite number of rad/s, got " +
                std::to_string(*options.yaw_rate_rad_s)};
  }
  if (options.angle_deg && !std::isfinite(*options.angle_deg)) {
    return {StatusCode::kInvalidArgument,
            "motion blur angle must be a finite number of degrees, got " +
                std::to_string(*options.angle_deg)};
  }
  return Status::ok();
}

// The corruptions without randomness whose one implementation serves both modes.
Result<cv::Mat> deterministic(const cv::Mat& bgr, Corruption type, int severity) {
  switch (type) {
    case Corruption::Contrast:
      return contrast(bgr, severity);
    case Corruption::Saturate:
      return saturate(bgr, severity);
    case Corruption::Pixelate:
      return pixelate(bgr, severity);
    case Corruption::JpegCompression:
      return jpeg_compression(bgr, severity);
    default:
      return Status(StatusCode::kInternal,
                    std::string("not a shared deterministic corruption: ") + to_string(type));
  }
}

cv::Mat rolling_shutter_of(const cv::Mat& bgr, int severity, const CorruptOptions& options) {
  if (!options.yaw_rate_rad_s) return bgr.clone();
  return rolling_shutter(bgr, severity, *options.yaw_rate_rad_s, options.focal_px);
}

// Two 32-bit draws make a sensor fault's 64-bit model seed.
std::uint64_t numpy_model_seed(rng::NumpyRandomState& rng) {
  const std::uint64_t hi = rng.next_u32();
  return (hi << 32) | rng.next_u32();
}

const std::vector<cv::Mat>& frost_set(const CorruptOptions& options) {
  static const std::vector<cv::Mat>
      kBuiltIn;  // empty: the frost functions use their built-in textures
  return options.frost_textures ? *options.frost_textures : kBuiltIn;
}

}  // namespace

Result<cv::Mat> corrupt(const cv::Mat& bgr, Corruption type, int severity,
                        rng::NumpyRandomState& rng, const CorruptOptions& options) {
  if (Status s = validate_input(bgr, severity); !s) return s;
  if (Status s = validate_options(options); !s) return s;
  if (severity == 0) return bgr.clone();
  switch (type) {
    // The table path is bit-identical to the HSV mirror (it falls back to it near truncation ties).
    case Corruption::Brightness:
      return brightness_fast(bgr, severity);
    case Corruption::ColorQuant:
      return color_quant(bgr, severity);
    case Corruption::MotionBlur: {
      const double angle = options.angle_deg ? *options.angle_deg : rng.uniform(-45.0, 45.0);
      return motion_blur_numpy(bgr, severity, angle);
    }
    // Blends straight from the plasma map's finest level (tested equal to plasma_fractal_crop +
    // fog_blend_exact).
    case Corruption::Fog:
      return fog_exact(bgr, severity, rng);
    case Corruption::Snow:
      return snow_exact(bgr, severity, rng);
    case Corruption::Dark:
      return dark_exact(bgr, severity, rng);
    case Corruption::GaussianNoise:
    case Corruption::ShotNoise:
    case Corruption::ImpulseNoise:
    case Corruption::SpeckleNoise:
    case Corruption::IsoNoise:
      return pointwise_noise_numpy(bgr, type, severity, rng);
    case Corruption::GaussianBlur:
      return gaussian_blur_exact(bgr, severity);
    case Corruption::Contrast:
    case Corruption::Saturate:
    case Corruption::Pixelate:
    case Corruption::JpegCompression:
      return deterministic(bgr, type, severity);
    case Corruption::DefocusBlur:
      return defocus_blur_exact(bgr, severity);
    case Corruption::GlassBlur:
      return glass_blur_numpy(bgr, severity, rng);
    case Corruption::ZoomBlur:
      return zoom_blur_exact(bgr, severity);
    case Corruption::Frost:
      return frost_numpy(bgr, severity, rng, frost_set(options));
    case Corruption::ElasticTransform:
      return elastic_transform_numpy(bgr, severity, rng);
    case Corruption::Spatter:
      return spatter_numpy(bgr, severity, rng);
    // Faultline's own: no reference to match; the model's seed is drawn from the numpy stream.
    case Corruption::Soiling:
    case Corruption::WaterDrops:
    case Corruption::Glare:
    case Corruption::ExposureFlicker:
      return sensor_fault(bgr, type, severity, numpy_model_seed(rng));
    case Corruption::TransportCorruption:
      return transport_corruption(bgr, severity, rng);
    case Corruption::Recompression:
      return recompression(bgr, severity);
    case Corruption::RollingShutter:
      return rolling_shutter_of(bgr, severity, options);
  }
  return Status(StatusCode::kInvalidArgument, "unknown corruption");
}

Result<cv::Mat> corrupt(const cv::Mat& bgr, Corruption type, int severity, rng::FastRng& rng,
                        const CorruptOptions& options) {
  if (Status s = validate_input(bgr, severity); !s) return s;
  if (Status s = validate_options(options); !s) return s;
  if (severity == 0) return bgr.clone();
  switch (type) {
    case Corruption::Brightness:
      return brightness_fast(bgr, severity);
    case Corruption::ColorQuant:
      return color_quant(bgr, severity);
    case Corruption::MotionBlur: {
      const double angle = options.angle_deg ? *options.angle_deg : rng.uniform(-45.0, 45.0);
      return motion_blur_fast(bgr, severity, angle);
    }
    case Corruption::Fog: {
      return fog_fast(bgr, severity, rng);
    }
    case Corruption::Snow:
      return snow_fast(bgr, severity, rng);
    case Corruption::Dark:
      return dark_fast(bgr, severity, rng);
    case Corruption::GaussianNoise:
    case Corruption::ShotNoise:
    case Corruption::ImpulseNoise:
    case Corruption::SpeckleNoise:
    case Corruption::IsoNoise:
      return pointwise_noise_fast(bgr, type, severity, rng);
    case Corruption::GaussianBlur:
      return gaussian_blur_fast(bgr, severity);
    case Corruption::Saturate:
      return saturate_fast(bgr, severity);
    case Corruption::Contrast:
    case Corruption::Pixelate:
    case Corruption::JpegCompression:
      return deterministic(bgr, type, severity);
    case Corruption::DefocusBlur:
      return defocus_blur_fast(bgr, severity);
    case Corruption::GlassBlur:
      return glass_blur_fast(bgr, severity, rng);
    case Corruption::ZoomBlur:
      return zoom_blur_fast(bgr, severity);
    case Corruption::Frost:
      return frost_fast(bgr, severity, rng, frost_set(options));
    case Corruption::ElasticTransform:
      return elastic_transform_fast(bgr, severity, rng);
    case Corruption::Spatter:
      return spatter_fast(bgr, severity, rng);
    case Corruption::Soiling:
    case Corruption::WaterDrops:
    case Corruption::Glare:
    case Corruption::ExposureFlicker:
      return sensor_fault(bgr, type, severity, rng.next_u64());
    case Corruption::TransportCorruption:
      return transport_corruption(bgr, severity, rng);
    case Corruption::Recompression:
      return recompression(bgr, severity);
    case Corruption::RollingShutter:
      return rolling_shutter_of(bgr, severity, options);
  }
  return Status(StatusCode::kInvalidArgument, "unknown corruption");
}

Result<cv::Mat> corrupt_seeded(const cv::Mat& bgr, Corruption type, int severity, RngMode mode,
                               std::uint32_t seed, const CorruptOptions& options) {
  if (mode == RngMode::Numpy) {
    rng::NumpyRandomState rng(seed);
    return corrupt(bgr, type, severity, rng, options);
  }
  rng::FastRng rng(seed);
  return corrupt(bgr, type, severity, rng, options);
}

}  // namespace faultline::corruption
