// Parsing of the injector's fault schedule; windows and severity ramps.
#include "policy/fault_spec.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>

#include "common/config.hpp"
#include "corruption/sensor_fault.hpp"
#include "policy/temporal_draws.hpp"

namespace faultline::policy {
namespace {

constexpr double kMaxStaleMs = 10'000;

const std::set<std::string> kKeys = {"type",     "level",  "severity", "cameras", "rng",
                                     "coherent", "mode",   "delay_ms", "start_s", "duration_s",
                                     "ramp_s",   "frames", "offset_ms"};

[[noreturn]] void fail(const std::string& where, const std::string& key, const std::string& value,
                       const std::string& why) {
  throw ConfigError(where + "." + key + " = " + value + ": " + why);
}

template <typename T>
T read(const YAML::Node& node, const std::string& where, const std::string& key,
       const char* expected) {
  try {
    if constexpr (std::is_same_v<T, bool>) {
      if (!node.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "not a scalar");
    }
    return node.as<T>();
  } catch (const YAML::Exception&) {
    fail(where, key, config::yaml_to_string(node), std::string("expected ") + expected);
  }
}

struct TypeName {
  const char* name;
  FaultKind kind;
};
constexpr TypeName kTemporal[] = {{"camera_crash", FaultKind::CameraCrash},
                                  {"frame_lost", FaultKind::FrameLost},
                                  {"black", FaultKind::Black},
                                  {"freeze", FaultKind::Freeze},
                                  {"drop", FaultKind::Drop},
                                  {"delay", FaultKind::Delay},
                                  {"calibration_drift", FaultKind::CalibrationDrift},
                                  {"timestamp_skew", FaultKind::TimestampSkew},
                                  {"stale_frames", FaultKind::StaleFrames}};

// camera_crash / frame_lost levels: the severities nuScenes-C used (p = 1/3, 2/3, 5/6 for
// frame_lost).
int temporal_severity(corruption::Level level) {
  switch (level) {
    case corruption::Level::Easy:
      return 2;
    case corruption::Level::Mid:
      return 4;
    case corruption::Level::Hard:
      return 5;
  }
  return 4;
}

bool set_type(FaultSpec& spec, const std::string& type) {
  if (auto c = corruption::corruption_from_string(type)) {
    spec.kind = FaultKind::Corruption;
    spec.corruption = *c;
    return true;
  }
  for (const auto& t : kTemporal) {
    if (type == t.name) {
      spec.kind = t.kind;
      return true;
    }
  }
  return false;
}

int level_severity(const FaultSpec& spec, corruption::Level level) {
  return spec.kind == FaultKind::Corruption ? corruption::severity_for(spec.corruption, level)
                                            : temporal_severity(level);
}

FaultSpec parse_one(const YAML::Node& node, const std::string& where) {
  if (!node.IsMap()) {
    throw ConfigError(where + " = " + config::yaml_to_string(node) +
                      ": expected a mapping with at least `type`");
  }
  for (const auto& kv : node) {
    // A list or mapping as key (YAML's `? [a, b] : v`): as<std::string> would throw yaml-cpp's own
    // error.
    if (!kv.first.IsScalar())
      fail(where, "(key)", config::yaml_to_string(kv.first), "a key must be a string");
    const auto key = kv.first.Scalar();
    if (!kKeys.count(key)) {
      fail(where, key, config::yaml_to_string(kv.second),
           "unknown key (expected type, level, severity, cameras, rng, coherent, mode, delay_ms, "
           "start_s, "
           "duration_s, ramp_s, frames, offset_ms)");
    }
  }
  FaultSpec spec;
  if (!node["type"]) fail(where, "type", "(missing)", "every fault needs a type");
  const auto type = read<std::string>(node["type"], where, "type", "string");
  if (!set_type(spec, type)) {
    fail(where, "type", type,
         "expected " + corruption::corruption_names("|") +
             "|camera_crash|frame_lost|black|freeze|drop|delay|calibration_drift|timestamp_skew"
             "|stale_frames");
  }
  if (node["level"] && node["severity"])
    fail(where, "level", config::yaml_to_string(node["level"]), "give level or severity, not both");
  // Scripted actions (black, freeze, drop, delay) have no strength: severity 1 unless given.
  const bool graded = spec.kind == FaultKind::Corruption || spec.kind == FaultKind::CameraCrash ||
                      spec.kind == FaultKind::FrameLost ||
                      spec.kind == FaultKind::CalibrationDrift ||
                      spec.kind == FaultKind::TimestampSkew || spec.kind == FaultKind::StaleFrames;
  spec.severity = graded ? level_severity(spec, corruption::Level::Mid) : 1;
  if (node["level"]) {
    const auto text = read<std::string>(node["level"], where, "level", "string");
    const auto level = corruption::level_from_string(text);
    if (!level) fail(where, "level", text, "expected easy|mid|hard");
    spec.severity = level_severity(spec, *level);
  }
  if (node["severity"]) {
    spec.severity = read<int>(node["severity"], where, "severity", "integer");
    if (spec.severity < 1 || spec.severity > 5)
      fail(where, "severity", std::to_string(spec.severity), "expected 1..5");
  }
  if (const auto cams = node["cameras"]) {
    if (cams.IsScalar()) {
      const auto text = cams.as<std::string>();
      if (text != "all") {
        const int idx = camera_index(text);
        if (idx < 0)
          fail(where, "cameras", text, "expected all, a camera name or a list of camera names");
        spec.cameras.push_back(idx);
      }
    } else {
      for (const auto& name : read<std::vector<std::string>>(cams, where, "cameras",
                                                             "all or a list of camera names")) {
        const int idx = camera_index(name);
        if (idx < 0)
          fail(where, "cameras", name, "unknown camera (expected CAM_FRONT, CAM_FRONT_RIGHT, ...)");
        if (std::find(spec.cameras.begin(), spec.cameras.end(), idx) == spec.cameras.end())
          spec.cameras.push_back(idx);
      }
      if (spec.cameras.empty())
        fail(where, "cameras", "[]", "expected at least one camera (or all)");
    }
  }
  if (node["rng"]) {
    const auto text = read<std::string>(node["rng"], where, "rng", "string");
    const auto mode = corruption::rng_mode_from_string(text);
    if (!mode) fail(where, "rng", text, "expected fast|numpy");
    spec.rng = *mode;
  }
  if (node["coherent"]) spec.coherent = read<bool>(node["coherent"], where, "coherent", "bool");
  // A sensor fault's cause (dirt, drops, a light source, a hunting exposure loop) persists:
  // coherent by default in fast mode; `coherent: false` (or rng: numpy) redraws it for every frame
  // instead.
  if (!node["coherent"] && spec.kind == FaultKind::Corruption &&
      corruption::is_sensor_fault(spec.corruption) && spec.rng == corruption::RngMode::Fast) {
    spec.coherent = true;
  }
  if (spec.coherent && spec.rng == corruption::RngMode::Numpy)
    fail(where, "coherent", "true", "coherent needs rng: fast");
  if (spec.coherent && spec.kind != FaultKind::Corruption)
    fail(where, "coherent", "true", "only image corruptions are coherent");
  if (spec.coherent && spec.corruption == corruption::Corruption::RollingShutter) {
    fail(where, "coherent", "true",
         "rolling_shutter follows the ego poses of the stream and keeps no other state");
  }
  if (node["mode"]) {
    const auto text = read<std::string>(node["mode"], where, "mode", "string");
    if (spec.kind != FaultKind::CameraCrash && spec.kind != FaultKind::FrameLost) {
      fail(where, "mode", text, "only camera_crash and frame_lost take a mode");
    }
    if (text == "black")
      spec.mode = OutputMode::Black;
    else if (text == "drop")
      spec.mode = OutputMode::Drop;
    else if (text == "freeze")
      spec.mode = OutputMode::Freeze;
    else if (text == "delay")
      spec.mode = OutputMode::Delay;
    else
      fail(where, "mode", text, "expected black|drop|freeze|delay");
  }
  auto non_negative = [&](const char* key, double& field) {
    if (!node[key]) return;
    field = read<double>(node[key], where, key, "number");
    if (!(field >= 0) || !std::isfinite(field))
      fail(where, key, config::yaml_to_string(node[key]), "expected a number >= 0");
  };
  non_negative("delay_ms", spec.delay_ms);
  if (node["delay_ms"] && spec.kind == FaultKind::StaleFrames) {
    // The lag is held in memory (every frame of the camera within it): a bound keeps a typo from
    // holding minutes of images.
    if (spec.delay_ms > kMaxStaleMs)
      fail(where, "delay_ms", config::yaml_to_string(node["delay_ms"]),
           "stale_frames lags at most 10000 ms");
    spec.lag_ms = spec.delay_ms;
  }
  non_negative("start_s", spec.start_s);
  non_negative("ramp_s", spec.ramp_s);
  if (node["duration_s"]) {
    double d = 0;
    non_negative("duration_s", d);
    spec.duration_s = d;
  }
  if (node["offset_ms"]) {
    const double ms = read<double>(node["offset_ms"], where, "offset_ms", "number");
    if (spec.kind != FaultKind::TimestampSkew)
      fail(where, "offset_ms", config::yaml_to_string(node["offset_ms"]),
           "only timestamp_skew takes offset_ms");
    if (!std::isfinite(ms) || std::abs(ms) > 1e6) {
      fail(where, "offset_ms", config::yaml_to_string(node["offset_ms"]),
           "expected a finite number of ms within +-1e6");
    }
    spec.offset_ms = ms;
  }
  if (node["frames"]) {
    const auto text = read<std::string>(node["frames"], where, "frames", "string");
    if (text == "key")
      spec.frames = FrameSet::Key;
    else if (text == "all")
      spec.frames = FrameSet::All;
    else
      fail(where, "frames", text, "expected key|all");
  }
  return spec;
}

}  // namespace

std::string FaultSpec::name() const {
  if (kind == FaultKind::Corruption) return corruption::to_string(corruption);
  for (const auto& t : kTemporal) {
    if (t.kind == kind) return t.name;
  }
  return "unknown";
}

bool FaultSpec::applies_to(int camera) const {
  return cameras.empty() || std::find(cameras.begin(), cameras.end(), camera) != cameras.end();
}

bool is_stream_fault(const std::string& type) {
  return std::any_of(std::begin(kTemporal), std::end(kTemporal),
                     [&](const TypeName& t) { return type == t.name; });
}

int camera_index(const std::string& name) {
  for (int i = 0; i < kNumCameras; ++i) {
    if (name == kCameraNames[i]) return i;
  }
  return -1;
}

const char* to_string(OutputMode mode) {
  switch (mode) {
    case OutputMode::Black:
      return "black";
    case OutputMode::Drop:
      return "drop";
    case OutputMode::Freeze:
      return "freeze";
    case OutputMode::Delay:
      return "delay";
  }
  return "black";
}

std::vector<FaultSpec> parse_faults(const YAML::Node& faults, const std::string& origin) {
  std::vector<FaultSpec> out;
  if (!faults || faults.IsNull()) return out;
  if (!faults.IsSequence())
    throw ConfigError(origin + ": faults = " + config::yaml_to_string(faults) +
                      ": expected a list");
  for (std::size_t i = 0; i < faults.size(); ++i) {
    out.push_back(parse_one(faults[i], origin + ": faults[" + std::to_string(i) + "]"));
  }
  return out;
}

std::optional<FaultSpec> parse_corruption_shorthand(const std::string& text,
                                                    const std::string& origin) {
  if (text.empty() || text == "none") return std::nullopt;
  const auto slash = text.find('/');
  YAML::Node node;
  node["type"] = text.substr(0, slash);
  if (slash != std::string::npos) {
    const std::string level = text.substr(slash + 1);
    // Digits go to `severity` as text: parse_one's integer check refuses what does not fit an int
    // (std::stoi threw std::out_of_range past the ConfigError handler).
    const bool digits =
        !level.empty() && std::all_of(level.begin(), level.end(),
                                      [](unsigned char c) { return std::isdigit(c) != 0; });
    if (digits)
      node["severity"] = level;
    else
      node["level"] = level;
  }
  try {
    return parse_one(node, origin + ": corruption");
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": corruption = " + text +
                      ": expected <type>/<easy|mid|hard|1..5> (" + e.what() + ")");
  }
}

int severity_at(const FaultSpec& spec, DurationNs elapsed_ns) {
  const double t = static_cast<double>(elapsed_ns) / 1e9 - spec.start_s;
  if (t < 0) return 0;
  if (spec.duration_s && t >= *spec.duration_s) return 0;
  if (spec.ramp_s <= 0 || t >= spec.ramp_s) return spec.severity;
  return std::min(spec.severity, 1 + static_cast<int>(std::floor(spec.severity * t / spec.ramp_s)));
}

}  // namespace faultline::policy
