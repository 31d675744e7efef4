// The eight nuScenes-C conditions as RoboBEV's generator names its output folders (spec
// corruptions.md §1.6-1.7), plus the imagecorruptions 1.1.2 corruptions nuScenes-C does not have
// (folders named by their PascalCase names).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.hpp"
#include "corruption/types.hpp"

namespace faultline::exporter {

// Reference loop order (spec §1.6): CameraCrash, FrameLost, MotionBlur, ColorQuant, Brightness,
// LowLight, Fog, Snow; then the further imagecorruptions / RoboBEV corruptions (docs/faults.md),
// which nuScenes-C does not have.
enum class Condition {
  CameraCrash,
  FrameLost,
  MotionBlur,
  ColorQuant,
  Brightness,
  LowLight,
  Fog,
  Snow,
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
  Soiling,
  WaterDrops,
  Glare,
  ExposureFlicker,
  TransportCorruption,  // Faultline's own pixel stream faults (docs/faults.md, "Stream and system
                        // faults")
  Recompression
};

// nuScenes-C's eight: what "all" selects.
inline constexpr Condition kAllConditions[] = {
    Condition::CameraCrash, Condition::FrameLost, Condition::MotionBlur, Condition::ColorQuant,
    Condition::Brightness,  Condition::LowLight,  Condition::Fog,        Condition::Snow};
// Every condition a list may name, in output order.
inline constexpr Condition kEveryCondition[] = {Condition::CameraCrash,
                                                Condition::FrameLost,
                                                Condition::MotionBlur,
                                                Condition::ColorQuant,
                                                Condition::Brightness,
                                                Condition::LowLight,
                                                Condition::Fog,
                                                Condition::Snow,
                                                Condition::GaussianNoise,
                                                Condition::ShotNoise,
                                                Condition::ImpulseNoise,
                                                Condition::SpeckleNoise,
                                                Condition::IsoNoise,
                                                Condition::Contrast,
                                                Condition::Saturate,
                                                Condition::Pixelate,
                                                Condition::JpegCompression,
                                                Condition::GaussianBlur,
                                                Condition::DefocusBlur,
                                                Condition::GlassBlur,
                                                Condition::ZoomBlur,
                                                Condition::Frost,
                                                Condition::ElasticTransform,
                                                Condition::Spatter,
                                                Condition::Soiling,
                                                Condition::WaterDrops,
                                                Condition::Glare,
                                                Condition::ExposureFlicker,
                                                Condition::TransportCorruption,
                                                Condition::Recompression};

// RoboBEV class name, used as the folder name ("CameraCrash"; "ISONoise" as RoboBEV spells it;
// CamelCase of the imagecorruptions name for the corruptions RoboBEV has no class for).
const char* class_name(Condition c);

// Accepts class names and imagecorruptions / snake_case names, case-insensitive ("fog",
// "low_light", "dark", "camera_crash", "CameraCrash").
std::optional<Condition> condition_from_string(std::string_view name);

// The image corruption behind a condition; nullopt for CameraCrash and FrameLost (black frames).
std::optional<corruption::Corruption> image_corruption(Condition c);

// Severity nuScenes-C uses: CameraCrash/FrameLost 2/4/5, the others per corruption::severity_for.
int severity_of(Condition c, corruption::Level level);

// Parses "all" (nuScenes-C's eight) or a comma-separated list of any conditions; the result is in
// the order of kEveryCondition (reference loop order first) without duplicates.
Result<std::vector<Condition>> parse_conditions(const std::string& list);
// Parses a comma-separated list of easy, mid, hard; result in easy, mid, hard order.
Result<std::vector<corruption::Level>> parse_levels(const std::string& list);

}  // namespace faultline::exporter
