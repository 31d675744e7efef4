// Parsing of the injector's fault schedule; windows and severity ramps.
#include "policy/fault_spec.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "corruption/sensor_fault.hpp"
#include "policy/temporal_draws.hpp"

namespace faultline::policy {
namespace {

// `cameras:` as written: one word (all, or a camera name) or a list of camera names.
struct CameraSelection {
  static constexpr const char* kTypeName = "all or a list of camera names";
  bool one_word = true;
  std::vector<std::string> names{"all"};
};

}  // namespace
}  // namespace faultline::policy

namespace YAML {
template <>
struct convert<faultline::policy::CameraSelection> {
  static Node encode(const faultline::policy::CameraSelection& c) {
    Node n;
    if (c.one_word)
      n = c.names.front();
    else
      n = c.names;
    return n;
  }
  static bool decode(const Node& node, faultline::policy::CameraSelection& c) {
    c.names.clear();
    c.one_word = node.IsScalar();
    if (c.one_word) {
      c.names.push_back(node.Scalar());
      return true;
    }
    if (!node.IsSequence()) return false;
    // Elements read as as<std::string> does: a null element is the name "null".
    for (const auto& item : node) c.names.push_back(item.as<std::string>());
    return true;
  }
};
}  // namespace YAML

namespace faultline::policy {
namespace {

constexpr double kMaxStaleMs = 10'000;

[[noreturn]] void fail(const std::string& where, const std::string& key, const std::string& value,
                       const std::string& why) {
  throw ConfigError(where + "." + key + " = " + value + ": " + why);
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

// A fault as written in the `faults` list: every key once, with its description (also the table
// of fault_keys_help()). Optional keys tell "not given" from a value where the default depends on
// the type; EntryResolver reads them and checks the values.
struct FaultEntry {
  std::optional<std::string> type;
  std::optional<std::string> level;
  std::optional<int> severity;
  std::optional<CameraSelection> cameras;
  std::string rng = "fast";
  std::optional<bool> coherent;
  std::optional<std::string> mode;
  std::optional<double> delay_ms;
  double start_s = 0;
  std::optional<double> duration_s;
  double ramp_s = 0;
  std::string frames = "all";
  std::optional<double> offset_ms;

  template <class V>
  void visit(V& v) {
    v("type", type,
      "required: an image corruption (fog, snow, ...: docs/faults.md) or camera_crash, "
      "frame_lost, black, freeze, drop, delay, calibration_drift, timestamp_skew, stale_frames");
    v("level", level, "easy|mid|hard, the type's severity for that level (not with severity)");
    v("severity", severity,
      "1..5, the ramp's top; none = the level's, else mid's (1 for black, freeze, drop, delay)");
    v("cameras", cameras, "camera names (CAM_FRONT, CAM_FRONT_RIGHT, ...) or all; none = all");
    v("rng", rng, "fast|numpy: numpy draws the reference's random stream (bit-exact)");
    v("coherent", coherent,
      "one lasting fault per camera, image corruptions with rng fast only; "
      "none = on for the sensor faults (soiling, water_drops, glare, exposure_flicker)");
    v("mode", mode, "camera_crash and frame_lost output: black|drop|freeze|delay; none = black");
    v("delay_ms", delay_ms,
      "ms >= 0: how long mode delay and type delay hold a frame (none = 200); stale_frames: "
      "the lag, at most 10000 (none = the severity's)");
    v("start_s", start_s, "window start, s >= 0 after the first frame's capture time");
    v("duration_s", duration_s, "window length, s >= 0; none = until the end");
    v("ramp_s", ramp_s, "s >= 0 of a linear severity ramp from 1 up to severity");
    v("frames", frames, "key|all: key frames only (nuScenes-C) or every frame incl. sweeps");
    v("offset_ms", offset_ms,
      "timestamp_skew only: stamp offset in ms, either sign, within +-1e6; none = the severity's");
  }
};

// Reads one entry key by key, each value checked before the next is read, in the order errors
// have always been reported: type, level/severity, cameras, rng, coherent, mode, delay_ms,
// start_s, ramp_s, duration_s, offset_ms, frames. Unknown keys were refused before.
class EntryResolver {
 public:
  EntryResolver(const YAML::Node& entry, const std::string& where)
      : loader_(entry, where), entry_(entry), where_(where) {}

  FaultSpec resolve() {
    resolve_type();
    resolve_severity();
    resolve_cameras();
    resolve_coherence();
    resolve_mode();
    resolve_timing();
    return spec_;
  }

 private:
  void read(const char* key) { config::load_field(loader_, e_, key); }

  [[noreturn]] void fail_as_written(const char* key, const std::string& why) const {
    fail(where_, key, config::yaml_to_string(entry_[key]), why);
  }

  void resolve_type() {
    read("type");
    if (!e_.type) fail(where_, "type", "(missing)", "every fault needs a type");
    if (!set_type(spec_, *e_.type)) {
      fail(where_, "type", *e_.type,
           "expected " + corruption::corruption_names("|") +
               "|camera_crash|frame_lost|black|freeze|drop|delay|calibration_drift"
               "|timestamp_skew|stale_frames");
    }
  }

  void resolve_severity() {
    if (entry_["level"] && entry_["severity"])
      fail_as_written("level", "give level or severity, not both");
    read("level");
    read("severity");
    // Scripted actions (black, freeze, drop, delay) have no strength: severity 1 unless given.
    const FaultKind k = spec_.kind;
    const bool graded = k == FaultKind::Corruption || k == FaultKind::CameraCrash ||
                        k == FaultKind::FrameLost || k == FaultKind::CalibrationDrift ||
                        k == FaultKind::TimestampSkew || k == FaultKind::StaleFrames;
    spec_.severity = graded ? level_severity(spec_, corruption::Level::Mid) : 1;
    if (e_.level) {
      const auto level = corruption::level_from_string(*e_.level);
      if (!level) fail(where_, "level", *e_.level, "expected easy|mid|hard");
      spec_.severity = level_severity(spec_, *level);
    }
    if (e_.severity) {
      spec_.severity = *e_.severity;
      if (spec_.severity < 1 || spec_.severity > 5)
        fail(where_, "severity", std::to_string(spec_.severity), "expected 1..5");
    }
  }

  void resolve_cameras() {
    read("cameras");
    if (!e_.cameras) return;
    const CameraSelection& cams = *e_.cameras;
    if (cams.one_word) {
      const std::string& text = cams.names.front();
      if (text == "all") return;
      const int idx = camera_index(text);
      if (idx < 0)
        fail(where_, "cameras", text, "expected all, a camera name or a list of camera names");
      spec_.cameras.push_back(idx);
      return;
    }
    for (const auto& name : cams.names) {
      const int idx = camera_index(name);
      if (idx < 0)
        fail(where_, "cameras", name, "unknown camera (expected CAM_FRONT, CAM_FRONT_RIGHT, ...)");
      if (std::find(spec_.cameras.begin(), spec_.cameras.end(), idx) == spec_.cameras.end())
        spec_.cameras.push_back(idx);
    }
    if (spec_.cameras.empty())
      fail(where_, "cameras", "[]", "expected at least one camera (or all)");
  }

  void resolve_coherence() {
    read("rng");
    const auto mode = corruption::rng_mode_from_string(e_.rng);
    if (!mode) fail(where_, "rng", e_.rng, "expected fast|numpy");
    spec_.rng = *mode;
    // A sensor fault's cause (dirt, drops, a light source, a hunting exposure loop) persists:
    // coherent by default in fast mode; `coherent: false` (or rng: numpy) redraws it for every
    // frame instead.
    read("coherent");
    if (e_.coherent) {
      spec_.coherent = *e_.coherent;
    } else {
      spec_.coherent = spec_.kind == FaultKind::Corruption &&
                       corruption::is_sensor_fault(spec_.corruption) &&
                       spec_.rng == corruption::RngMode::Fast;
    }
    if (!spec_.coherent) return;
    if (spec_.rng == corruption::RngMode::Numpy)
      fail(where_, "coherent", "true", "coherent needs rng: fast");
    if (spec_.kind != FaultKind::Corruption)
      fail(where_, "coherent", "true", "only image corruptions are coherent");
    if (spec_.corruption == corruption::Corruption::RollingShutter) {
      fail(where_, "coherent", "true",
           "rolling_shutter follows the ego poses of the stream and keeps no other state");
    }
  }

  void resolve_mode() {
    read("mode");
    if (!e_.mode) return;
    const std::string& text = *e_.mode;
    if (spec_.kind != FaultKind::CameraCrash && spec_.kind != FaultKind::FrameLost)
      fail(where_, "mode", text, "only camera_crash and frame_lost take a mode");
    if (text == "black")
      spec_.mode = OutputMode::Black;
    else if (text == "drop")
      spec_.mode = OutputMode::Drop;
    else if (text == "freeze")
      spec_.mode = OutputMode::Freeze;
    else if (text == "delay")
      spec_.mode = OutputMode::Delay;
    else
      fail(where_, "mode", text, "expected black|drop|freeze|delay");
  }

  void check_non_negative(const char* key, double value) const {
    if (!(value >= 0) || !std::isfinite(value)) fail_as_written(key, "expected a number >= 0");
  }

  void resolve_timing() {
    read("delay_ms");
    if (e_.delay_ms) {
      check_non_negative("delay_ms", *e_.delay_ms);
      spec_.delay_ms = *e_.delay_ms;
      if (spec_.kind == FaultKind::StaleFrames) {
        // The lag is held in memory (every frame of the camera within it): a bound keeps a typo
        // from holding minutes of images.
        if (spec_.delay_ms > kMaxStaleMs)
          fail_as_written("delay_ms", "stale_frames lags at most 10000 ms");
        spec_.lag_ms = spec_.delay_ms;
      }
    }
    read("start_s");
    check_non_negative("start_s", e_.start_s);
    spec_.start_s = e_.start_s;
    read("ramp_s");
    check_non_negative("ramp_s", e_.ramp_s);
    spec_.ramp_s = e_.ramp_s;
    read("duration_s");
    if (e_.duration_s) {
      check_non_negative("duration_s", *e_.duration_s);
      spec_.duration_s = *e_.duration_s;
    }
    read("offset_ms");
    if (e_.offset_ms) {
      const double ms = *e_.offset_ms;
      if (spec_.kind != FaultKind::TimestampSkew)
        fail_as_written("offset_ms", "only timestamp_skew takes offset_ms");
      if (!std::isfinite(ms) || std::abs(ms) > 1e6)
        fail_as_written("offset_ms", "expected a finite number of ms within +-1e6");
      spec_.offset_ms = ms;
    }
    read("frames");
    if (e_.frames == "key")
      spec_.frames = FrameSet::Key;
    else if (e_.frames == "all")
      spec_.frames = FrameSet::All;
    else
      fail(where_, "frames", e_.frames, "expected key|all");
  }

  config::Loader loader_;
  const YAML::Node& entry_;
  const std::string& where_;
  FaultEntry e_;
  FaultSpec spec_;
};

FaultSpec parse_one(const YAML::Node& node, const std::string& where) {
  if (!node.IsMap()) {
    throw ConfigError(where + " = " + config::yaml_to_string(node) +
                      ": expected a mapping with at least `type`");
  }
  config::check_entry_keys<FaultEntry>(node, where);
  return EntryResolver(node, where).resolve();
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

std::string fault_keys_help() { return config::help_table(FaultEntry{}); }

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
