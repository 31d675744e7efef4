#include "export/conditions.hpp"

#include <algorithm>
#include <cctype>

namespace faultline::exporter {
namespace {

std::string lower_without_underscores(std::string_view s) {
  std::string out;
  for (char ch : s) {
    if (ch == '_' || ch == '-') continue;
    out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(ch))));
  }
  return out;
}

std::vector<std::string> split_commas(const std::string& list) {
  std::vector<std::string> parts;
  std::string cur;
  for (char ch : list + ",") {
    if (ch == ',') {
      if (!cur.empty()) parts.push_back(cur);
      cur.clear();
    } else if (ch != ' ') {
      cur.push_back(ch);
    }
  }
  return parts;
}

std::string every_class_name() {
  std::string out;
  for (Condition c : kEveryCondition) out += (out.empty() ? "" : ", ") + std::string(class_name(c));
  return out;
}

}  // namespace

const char* class_name(Condition c) {
  switch (c) {
    case Condition::CameraCrash:
      return "CameraCrash";
    case Condition::FrameLost:
      return "FrameLost";
    case Condition::MotionBlur:
      return "MotionBlur";
    case Condition::ColorQuant:
      return "ColorQuant";
    case Condition::Brightness:
      return "Brightness";
    case Condition::LowLight:
      return "LowLight";
    case Condition::Fog:
      return "Fog";
    case Condition::Snow:
      return "Snow";
    case Condition::GaussianNoise:
      return "GaussianNoise";
    case Condition::ShotNoise:
      return "ShotNoise";
    case Condition::ImpulseNoise:
      return "ImpulseNoise";
    case Condition::SpeckleNoise:
      return "SpeckleNoise";
    case Condition::IsoNoise:
      return "ISONoise";
    case Condition::Contrast:
      return "Contrast";
    case Condition::Saturate:
      return "Saturate";
    case Condition::Pixelate:
      return "Pixelate";
    case Condition::JpegCompression:
      return "JpegCompression";
    case Condition::GaussianBlur:
      return "GaussianBlur";
    case Condition::DefocusBlur:
      return "DefocusBlur";
    case Condition::GlassBlur:
      return "GlassBlur";
    case Condition::ZoomBlur:
      return "ZoomBlur";
    case Condition::Frost:
      return "Frost";
    case Condition::ElasticTransform:
      return "ElasticTransform";
    case Condition::Spatter:
      return "Spatter";
    case Condition::Soiling:
      return "Soiling";
    case Condition::WaterDrops:
      return "WaterDrops";
    case Condition::Glare:
      return "Glare";
    case Condition::ExposureFlicker:
      return "ExposureFlicker";
    case Condition::TransportCorruption:
      return "TransportCorruption";
    case Condition::Recompression:
      return "Recompression";
  }
  return "?";
}

std::optional<Condition> condition_from_string(std::string_view name) {
  const std::string key = lower_without_underscores(name);
  for (Condition c : kEveryCondition) {
    if (key == lower_without_underscores(class_name(c))) return c;
  }
  if (key == "dark") return Condition::LowLight;
  if (key == "bright") return Condition::Brightness;
  return std::nullopt;
}

std::optional<corruption::Corruption> image_corruption(Condition c) {
  using corruption::Corruption;
  switch (c) {
    case Condition::MotionBlur:
      return Corruption::MotionBlur;
    case Condition::ColorQuant:
      return Corruption::ColorQuant;
    case Condition::Brightness:
      return Corruption::Brightness;
    case Condition::LowLight:
      return Corruption::Dark;
    case Condition::Fog:
      return Corruption::Fog;
    case Condition::Snow:
      return Corruption::Snow;
    case Condition::GaussianNoise:
      return Corruption::GaussianNoise;
    case Condition::ShotNoise:
      return Corruption::ShotNoise;
    case Condition::ImpulseNoise:
      return Corruption::ImpulseNoise;
    case Condition::SpeckleNoise:
      return Corruption::SpeckleNoise;
    case Condition::IsoNoise:
      return Corruption::IsoNoise;
    case Condition::Contrast:
      return Corruption::Contrast;
    case Condition::Saturate:
      return Corruption::Saturate;
    case Condition::Pixelate:
      return Corruption::Pixelate;
    case Condition::JpegCompression:
      return Corruption::JpegCompression;
    case Condition::GaussianBlur:
      return Corruption::GaussianBlur;
    case Condition::DefocusBlur:
      return Corruption::DefocusBlur;
    case Condition::GlassBlur:
      return Corruption::GlassBlur;
    case Condition::ZoomBlur:
      return Corruption::ZoomBlur;
    case Condition::Frost:
      return Corruption::Frost;
    case Condition::ElasticTransform:
      return Corruption::ElasticTransform;
    case Condition::Spatter:
      return Corruption::Spatter;
    case Condition::Soiling:
      return Corruption::Soiling;
    case Condition::WaterDrops:
      return Corruption::WaterDrops;
    case Condition::Glare:
      return Corruption::Glare;
    case Condition::ExposureFlicker:
      return Corruption::ExposureFlicker;
    case Condition::TransportCorruption:
      return Corruption::TransportCorruption;
    case Condition::Recompression:
      return Corruption::Recompression;
    case Condition::CameraCrash:
    case Condition::FrameLost:
      return std::nullopt;
  }
  return std::nullopt;
}

int severity_of(Condition c, corruption::Level level) {
  if (auto img = image_corruption(c)) return corruption::severity_for(*img, level);
  switch (level) {  // RoboBEV nuscenes_c.py: CameraCrash / FrameLost 2, 4, 5
    case corruption::Level::Easy:
      return 2;
    case corruption::Level::Mid:
      return 4;
    case corruption::Level::Hard:
      return 5;
  }
  return 0;
}

Result<std::vector<Condition>> parse_conditions(const std::string& list) {
  if (lower_without_underscores(list) == "all") {
    return std::vector<Condition>(std::begin(kAllConditions), std::end(kAllConditions));
  }
  std::vector<bool> wanted(std::size(kEveryCondition), false);
  const auto parts = split_commas(list);
  if (parts.empty()) return Status(StatusCode::kInvalidArgument, "empty corruption list");
  for (const auto& p : parts) {
    const auto c = condition_from_string(p);
    if (!c) {
      return Status(StatusCode::kInvalidArgument,
                    "unknown corruption '" + p + "' (expected all or " + every_class_name() + ")");
    }
    wanted[static_cast<std::size_t>(*c)] = true;
  }
  std::vector<Condition> out;
  for (Condition c : kEveryCondition) {
    if (wanted[static_cast<std::size_t>(c)]) out.push_back(c);
  }
  return out;
}

Result<std::vector<corruption::Level>> parse_levels(const std::string& list) {
  std::vector<bool> wanted(3, false);
  const auto parts = split_commas(list);
  if (parts.empty()) return Status(StatusCode::kInvalidArgument, "empty level list");
  for (const auto& p : parts) {
    const auto l = corruption::level_from_string(p);
    if (!l)
      return Status(StatusCode::kInvalidArgument,
                    "unknown level '" + p + "' (expected easy, mid, hard)");
    wanted[static_cast<std::size_t>(*l)] = true;
  }
  std::vector<corruption::Level> out;
  for (auto l : corruption::kAllLevels) {
    if (wanted[static_cast<std::size_t>(l)]) out.push_back(l);
  }
  return out;
}

}  // namespace faultline::exporter
