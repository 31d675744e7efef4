// The eight nuScenes-C conditions as RoboBEV's generator names its output folders (spec corruptions.md §1.6-1.7).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.hpp"
#include "corruption/types.hpp"

namespace faultline::exporter {

// Reference loop order (spec §1.6): CameraCrash, FrameLost, MotionBlur, ColorQuant, Brightness, LowLight, Fog, Snow.
enum class Condition { CameraCrash, FrameLost, MotionBlur, ColorQuant, Brightness, LowLight, Fog, Snow };

inline constexpr Condition kAllConditions[] = {Condition::CameraCrash, Condition::FrameLost, Condition::MotionBlur,
                                               Condition::ColorQuant,  Condition::Brightness, Condition::LowLight,
                                               Condition::Fog,         Condition::Snow};

// RoboBEV class name, used as the folder name ("CameraCrash").
const char* class_name(Condition c);

// Accepts class names and imagecorruptions / snake_case names, case-insensitive ("fog", "low_light", "dark",
// "camera_crash", "CameraCrash").
std::optional<Condition> condition_from_string(std::string_view name);

// The image corruption behind a condition; nullopt for CameraCrash and FrameLost (black frames).
std::optional<corruption::Corruption> image_corruption(Condition c);

// Severity nuScenes-C uses: CameraCrash/FrameLost 2/4/5, the others per corruption::severity_for.
int severity_of(Condition c, corruption::Level level);

// Parses "all" or a comma-separated list; the result is in reference loop order without duplicates.
Result<std::vector<Condition>> parse_conditions(const std::string& list);
// Parses a comma-separated list of easy, mid, hard; result in easy, mid, hard order.
Result<std::vector<corruption::Level>> parse_levels(const std::string& list);

}  // namespace faultline::exporter
