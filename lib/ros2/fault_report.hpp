// What a fault run did to one frame, as the diagnostic_msgs/DiagnosticArray Faultline writes on
// /faultline/faults of a rosbag2 (`bag convert --format ros2` and `bag corrupt` both build their
// reports here): one DiagnosticStatus whose message is the action and the faults ("corrupt fog/3")
// and whose values are the writer's own (action, source_seq, ...) followed by each fault's
// severity, seed, rng and parameters. Pure; thread-safe.
//
// The level follows the action, one rule for every writer (ros2_out's live reports too): OK for
// "pass"; WARN when the frame still arrives with its content, changed or late ("corrupt",
// "delay"); ERROR when the frame's content is lost ("drop", "black", "freeze") or the fault asked
// for could not be applied ("undecodable"), and for any other action.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "ros2/messages.hpp"

namespace faultline::ros2 {

struct ReportedFault {
  std::string name;              // "fog"
  std::int64_t severity = 0;     // 1..5
  std::uint64_t seed = 0;        // the draw's effective seed
  std::string rng;               // "numpy" or "fast"
  std::vector<KeyValue> params;  // parameter name -> fault_param_text(value), in name order
};

struct FaultReport {
  Header header;                      // the frame's stamp and frame_id
  std::string name;                   // "faultline/<camera>" or "faultline<topic>"
  std::string hardware_id;            // the camera or frame_id
  std::string action;                 // "pass", "corrupt", "drop", ...; sets the level
  std::string why;                    // appended to the message as ": <why>"; "" = nothing
  std::vector<KeyValue> values;       // written before the faults' values
  std::vector<ReportedFault> faults;  // in the order applied
};

// The DiagnosticStatus level of `action` (the rule above).
std::uint8_t fault_level(std::string_view action);

// A fault parameter as reports write it: the shortest text that reads back as the same double
// ("0.1", "3", "2.5e-07"; "nan", "inf", "-inf").
std::string fault_param_text(double value);

// A fault with its parameters (any order in, name order out) as fault_param_text writes them.
ReportedFault reported_fault(std::string name, std::int64_t severity, std::uint64_t seed,
                             std::string rng, const std::map<std::string, double>& params);

// The report as a one-status DiagnosticArray. Level: fault_level(action). Message: action, then
// " <name>/<severity>" per fault, then ": <why>" when set. Values: report.values, then per fault
// <name>.severity, <name>.seed, <name>.rng and <name>.<param> for each param.
DiagnosticArray to_diagnostic_array(const FaultReport& report);

}  // namespace faultline::ros2
