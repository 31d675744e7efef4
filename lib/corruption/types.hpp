// Corruption names, severities and nuScenes-C levels (spec corruptions.md §0, golden README
// "Severity").
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "common/status.hpp"

namespace faultline::corruption {

// The image corruptions: nuScenes-C's six, then imagecorruptions 1.1.2's pointwise ones and
// RoboBEV's ISONoise, then its blur/weather/digital ones, then Faultline's own sensor faults and
// its stream and system faults (docs/faults.md). to_string/from_string use the imagecorruptions
// names ("motion_blur", "iso_noise").
enum class Corruption {
  Brightness,
  Dark,
  Fog,
  Snow,
  MotionBlur,
  ColorQuant,
  GaussianNoise,
  ShotNoise,
  ImpulseNoise,
  SpeckleNoise,
  IsoNoise,
  Contrast,
  Saturate,
  Pixelate,
  JpegCompression,
  GaussianBlur,
  DefocusBlur,
  GlassBlur,
  ZoomBlur,
  Frost,
  ElasticTransform,
  Spatter,
  // Faultline's own sensor faults (sensor_fault.hpp); no reference has them.
  Soiling,
  WaterDrops,
  Glare,
  ExposureFlicker,
  // Faultline's own stream and system faults (no reference has them).
  TransportCorruption,
  Recompression,
  RollingShutter,
};

inline constexpr Corruption kAllCorruptions[] = {Corruption::Brightness,
                                                 Corruption::Dark,
                                                 Corruption::Fog,
                                                 Corruption::Snow,
                                                 Corruption::MotionBlur,
                                                 Corruption::ColorQuant,
                                                 Corruption::GaussianNoise,
                                                 Corruption::ShotNoise,
                                                 Corruption::ImpulseNoise,
                                                 Corruption::SpeckleNoise,
                                                 Corruption::IsoNoise,
                                                 Corruption::Contrast,
                                                 Corruption::Saturate,
                                                 Corruption::Pixelate,
                                                 Corruption::JpegCompression,
                                                 Corruption::GaussianBlur,
                                                 Corruption::DefocusBlur,
                                                 Corruption::GlassBlur,
                                                 Corruption::ZoomBlur,
                                                 Corruption::Frost,
                                                 Corruption::ElasticTransform,
                                                 Corruption::Spatter,
                                                 Corruption::Soiling,
                                                 Corruption::WaterDrops,
                                                 Corruption::Glare,
                                                 Corruption::ExposureFlicker,
                                                 Corruption::TransportCorruption,
                                                 Corruption::Recompression,
                                                 Corruption::RollingShutter};

// The paper's three levels; each corruption maps them to its own severities.
enum class Level { Easy, Mid, Hard };
inline constexpr Level kAllLevels[] = {Level::Easy, Level::Mid, Level::Hard};

// numpy: bit-exact with the Python reference seeded by np.random.seed. fast: statistically
// equivalent.
enum class RngMode { Numpy, Fast };

const char* to_string(Corruption c);
// Accepts the imagecorruptions names plus the manifest's RoboBEV aliases ("low_light" -> Dark).
std::optional<Corruption> corruption_from_string(std::string_view name);
// Every name to_string gives, in kAllCorruptions order, joined by `separator` (help texts and error
// messages).
std::string corruption_names(std::string_view separator = ", ");

const char* to_string(Level level);
std::optional<Level> level_from_string(std::string_view name);

const char* to_string(RngMode mode);
std::optional<RngMode> rng_mode_from_string(std::string_view name);

// Severity used by nuScenes-C for a level: Bright/Fog/MotionBlur 2/4/5, ColorQuant/Snow 1/2/3, Dark
// 2/3/4. The pointwise corruptions nuScenes-C does not have use 1/3/5, except ISONoise: it indexes
// its list like Dark (and stops at 4 in the reference), so it takes Dark's 2/3/4; the
// blur/weather/digital ones take 2/4/5 like Fog and Motion Blur (docs/faults.md); so do the sensor
// faults; Faultline's stream faults use 1/3/5.
int severity_for(Corruption c, Level level);

// Severity 0 means "off" (identity); 1..5 are the reference's numbers. Anything else is
// kInvalidArgument.
Status validate_severity(int severity);

// Whether the corruption draws random numbers (Bright, Color Quant, Contrast, Saturate, Pixelate,
// JPEG, Gaussian, Defocus and Zoom blur, Recompression and Rolling Shutter do not).
bool is_random(Corruption c);

}  // namespace faultline::corruption
