// The injector's fault schedule: the `faults` YAML list (or the `corruption: fog/mid` shorthand)
// parsed into FaultSpecs, plus the time window and linear severity ramp of each fault. Unknown
// keys, wrong types and out-of-range values are ConfigErrors naming the key and value
// ("fault_injector: faults[0].level = x: ...").
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "corruption/types.hpp"

namespace faultline::policy {

// What a fault does: an image corruption, one of the two RoboBEV temporal faults, a scripted output
// action, or one of Faultline's message faults (policy/message_faults.hpp: the frame's calibration
// or stamp, or its output time for stale_frames; pixels untouched).
enum class FaultKind {
  Corruption,
  CameraCrash,
  FrameLost,
  Black,
  Freeze,
  Drop,
  Delay,
  CalibrationDrift,
  TimestampSkew,
  StaleFrames
};
// How a camera_crash / frame_lost hit is rendered. Black is the reference's behaviour.
enum class OutputMode { Black, Drop, Freeze, Delay };
// Which frames a fault may touch: key frames only (nuScenes-C) or every frame incl. sweeps
// (streaming).
enum class FrameSet { Key, All };

struct FaultSpec {
  FaultKind kind = FaultKind::Corruption;
  corruption::Corruption corruption = corruption::Corruption::Fog;  // kind == Corruption only
  int severity = 1;                                                 // 1..5 (the ramp's top)
  std::vector<int> cameras;  // indices into kCameraNames; empty = all cameras
  corruption::RngMode rng = corruption::RngMode::Fast;
  bool coherent = false;                // CoherentCorruptor per camera (fast mode only)
  OutputMode mode = OutputMode::Black;  // camera_crash / frame_lost
  double delay_ms = 200;                // mode delay / kind Delay
  std::optional<double> offset_ms;  // timestamp_skew: stamp offset (either sign); none = severity's
  std::optional<double> lag_ms;     // stale_frames: its `delay_ms:` (the lag); none = severity's
  double start_s = 0;               // window start, relative to the first frame's capture time
  std::optional<double> duration_s;  // none = until the end
  double ramp_s = 0;                 // linear severity ramp 1 -> severity over this time
  FrameSet frames = FrameSet::All;

  std::string name() const;  // "fog", "camera_crash", "black", ...
  bool applies_to(int camera_index) const;
};

// Parses the `faults` list. `origin` prefixes error messages ("fault_injector"). A null node gives
// no faults.
std::vector<FaultSpec> parse_faults(const YAML::Node& faults, const std::string& origin);

// The keys of one `faults` entry as a --help table: key, type, default, description.
std::string fault_keys_help();

// "fog/mid", "fog/3", "camera_crash/hard" or "" (none): one fault on all cameras, fast mode, every
// frame.
std::optional<FaultSpec> parse_corruption_shorthand(const std::string& text,
                                                    const std::string& origin);

// Severity in effect `elapsed_ns` after the first frame: 0 outside the window, else 1..severity
// along the ramp (each of the `severity` steps lasts ramp_s / severity).
int severity_at(const FaultSpec& spec, DurationNs elapsed_ns);

// Whether `type` names a fault that acts on a stream, not on pixels (camera_crash, frame_lost,
// black, freeze, drop, delay, calibration_drift, timestamp_skew, stale_frames): tools that corrupt
// one image refuse these by name.
bool is_stream_fault(const std::string& type);

// Index of a camera name in kCameraNames, or -1.
int camera_index(const std::string& name);

const char* to_string(OutputMode mode);

}  // namespace faultline::policy
