// What the injector did to a frame (a Faultline FaultEvent) as the fields of a ROS 2
// diagnostic_msgs/DiagnosticArray with one DiagnosticStatus, so that `ros2 topic echo`,
// rqt_runtime_monitor or Foxglove show it without Faultline's own types. Pure; thread-safe.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "common/clock.hpp"
#include "fault.pb.h"

namespace faultline::ros2dds {

// diagnostic_msgs/DiagnosticStatus levels.
enum class DiagnosticLevel : std::uint8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };

struct DiagnosticValues {
  StampNs stamp_ns = 0;  // the frame's capture stamp (header.stamp)
  std::string frame_id;  // the frame's frame_id
  // ros2::fault_level's rule, as the bags' reports: OK passed; WARN corrupted or delayed; ERROR
  // dropped, black or frozen (the frame's content is lost).
  DiagnosticLevel level = DiagnosticLevel::kOk;
  std::string name;         // "faultline/<camera>"
  std::string message;      // action and faults: "corrupt: fog/3", "pass", "drop: frame_lost/2"
  std::string hardware_id;  // the camera
  std::vector<std::pair<std::string, std::string>>
      values;  // action, source_seq, sample_token, fault[i].*
};

// One status per event; values list action, source_seq, sample_token (when set),
// injector_latency_ns, then per fault i: fault<i>.name, fault<i>.severity, fault<i>.seed,
// fault<i>.rng and fault<i>.<param> (sorted by name).
DiagnosticValues diagnostic_from_event(const msgs::FaultEvent& event);

// "pass", "corrupt", "drop", "black", "freeze", "delay".
const char* action_name(msgs::FaultAction action);

}  // namespace faultline::ros2dds
