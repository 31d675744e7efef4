// What a fault run did to one frame, as the diagnostic_msgs/DiagnosticArray Faultline writes on
// /faultline/faults of a rosbag2 (`bag convert --format ros2`, and the layout `bag corrupt`
// follows): one DiagnosticStatus whose message is the action and the faults ("corrupt fog/3") and
// whose values are the writer's own (action, source_seq, ...) followed by each fault's severity,
// seed, rng and parameters. Pure; thread-safe.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ros2/messages.hpp"

namespace faultline::ros2 {

struct ReportedFault {
  std::string name;              // "fog"
  std::int64_t severity = 0;     // 1..5
  std::uint64_t seed = 0;        // the draw's effective seed
  std::string rng;               // "numpy" or "fast"
  std::vector<KeyValue> params;  // parameter name -> value as the writer formats it, in order
};

struct FaultReport {
  Header header;                               // the frame's stamp and frame_id
  std::uint8_t level = DiagnosticStatus::kOk;  // OK pass, WARN changed, ERROR content lost
  std::string name;                            // "faultline/<camera>" or "faultline<topic>"
  std::string hardware_id;                     // the camera or frame_id
  std::string action;                          // "pass", "corrupt", "drop", ...
  std::string why;                             // appended to the message as ": <why>"; "" = nothing
  std::vector<KeyValue> values;                // written before the faults' values
  std::vector<ReportedFault> faults;           // in the order applied
};

// The report as a one-status DiagnosticArray. Message: action, then " <name>/<severity>" per
// fault, then ": <why>" when set. Values: report.values, then per fault <name>.severity,
// <name>.seed, <name>.rng and <name>.<param> for each param.
DiagnosticArray to_diagnostic_array(const FaultReport& report);

}  // namespace faultline::ros2
