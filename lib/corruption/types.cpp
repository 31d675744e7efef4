// Name and level tables for the corruptions.
#include "corruption/types.hpp"

namespace faultline::corruption {

const char* to_string(Corruption c) {
  switch (c) {
    case Corruption::Brightness:
      return "brightness";
    case Corruption::Dark:
      return "dark";
    case Corruption::Fog:
      return "fog";
    case Corruption::Snow:
      return "snow";
    case Corruption::MotionBlur:
      return "motion_blur";
    case Corruption::ColorQuant:
      return "color_quant";
    case Corruption::GaussianNoise:
      return "gaussian_noise";
    case Corruption::ShotNoise:
      return "shot_noise";
    case Corruption::ImpulseNoise:
      return "impulse_noise";
    case Corruption::SpeckleNoise:
      return "speckle_noise";
    case Corruption::IsoNoise:
      return "iso_noise";
    case Corruption::Contrast:
      return "contrast";
    case Corruption::Saturate:
      return "saturate";
    case Corruption::Pixelate:
      return "pixelate";
    case Corruption::JpegCompression:
      return "jpeg_compression";
    case Corruption::GaussianBlur:
      return "gaussian_blur";
    case Corruption::DefocusBlur:
      return "defocus_blur";
    case Corruption::GlassBlur:
      return "glass_blur";
    case Corruption::ZoomBlur:
      return "zoom_blur";
    case Corruption::Frost:
      return "frost";
    case Corruption::ElasticTransform:
      return "elastic_transform";
    case Corruption::Spatter:
      return "spatter";
    case Corruption::Soiling:
      return "soiling";
    case Corruption::WaterDrops:
      return "water_drops";
    case Corruption::Glare:
      return "glare";
    case Corruption::ExposureFlicker:
      return "exposure_flicker";
    case Corruption::TransportCorruption:
      return "transport_corruption";
    case Corruption::Recompression:
      return "recompression";
    case Corruption::RollingShutter:
      return "rolling_shutter";
  }
  return "unknown";
}

std::optional<Corruption> corruption_from_string(std::string_view name) {
  for (Corruption c : kAllCorruptions) {
    if (name == to_string(c)) return c;
  }
  if (name == "low_light") return Corruption::Dark;
  if (name == "bright") return Corruption::Brightness;
  return std::nullopt;
}

std::string corruption_names(std::string_view separator) {
  std::string out;
  for (Corruption c : kAllCorruptions) {
    if (!out.empty()) out += separator;
    out += to_string(c);
  }
  return out;
}

const char* to_string(Level level) {
  switch (level) {
    case Level::Easy:
      return "easy";
    case Level::Mid:
      return "mid";
    case Level::Hard:
      return "hard";
  }
  return "unknown";
}

std::optional<Level> level_from_string(std::string_view name) {
  for (Level l : kAllLevels) {
    if (name == to_string(l)) return l;
  }
  return std::nullopt;
}

const char* to_string(RngMode mode) { return mode == RngMode::Numpy ? "numpy" : "fast"; }

std::optional<RngMode> rng_mode_from_string(std::string_view name) {
  if (name == "numpy") return RngMode::Numpy;
  if (name == "fast") return RngMode::Fast;
  return std::nullopt;
}

int severity_for(Corruption c, Level level) {
  const int index = static_cast<int>(level);
  switch (c) {
    case Corruption::ColorQuant:
    case Corruption::Snow:
      return 1 + index;
    case Corruption::Dark:
    case Corruption::IsoNoise:
      return 2 + index;
    case Corruption::Brightness:
    case Corruption::Fog:
    case Corruption::MotionBlur:
    case Corruption::DefocusBlur:
    case Corruption::GlassBlur:
    case Corruption::ZoomBlur:
    case Corruption::Frost:
    case Corruption::ElasticTransform:
    case Corruption::Spatter:
    case Corruption::Soiling:
    case Corruption::WaterDrops:
    case Corruption::Glare:
    case Corruption::ExposureFlicker:
      return index == 0 ? 2 : (index == 1 ? 4 : 5);
    case Corruption::GaussianNoise:
    case Corruption::ShotNoise:
    case Corruption::ImpulseNoise:
    case Corruption::SpeckleNoise:
    case Corruption::Contrast:
    case Corruption::Saturate:
    case Corruption::Pixelate:
    case Corruption::JpegCompression:
    case Corruption::GaussianBlur:
    case Corruption::TransportCorruption:
    case Corruption::Recompression:
    case Corruption::RollingShutter:
      return 1 + 2 * index;
  }
  return 1;
}

Status validate_severity(int severity) {
  if (severity < 0 || severity > 5) {
    return {StatusCode::kInvalidArgument,
            "severity " + std::to_string(severity) + " out of range: expected 1..5"};
  }
  return Status::ok();
}

bool is_random(Corruption c) {
  switch (c) {
    case Corruption::Brightness:
    case Corruption::ColorQuant:
    case Corruption::Contrast:
    case Corruption::Saturate:
    case Corruption::Pixelate:
    case Corruption::JpegCompression:
    case Corruption::GaussianBlur:
    case Corruption::DefocusBlur:
    case Corruption::ZoomBlur:
    case Corruption::Recompression:
    case Corruption::RollingShutter:
      return false;
    default:
      return true;
  }
}

}  // namespace faultline::corruption
