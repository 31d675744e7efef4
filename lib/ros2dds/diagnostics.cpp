#include "ros2dds/diagnostics.hpp"

#include <fmt/format.h>

#include <map>

#include "ros2/fault_report.hpp"

namespace faultline::ros2dds {

const char* action_name(msgs::FaultAction action) {
  switch (action) {
    case msgs::FAULT_ACTION_PASS:
      return "pass";
    case msgs::FAULT_ACTION_CORRUPT:
      return "corrupt";
    case msgs::FAULT_ACTION_DROP:
      return "drop";
    case msgs::FAULT_ACTION_BLACK:
      return "black";
    case msgs::FAULT_ACTION_FREEZE:
      return "freeze";
    case msgs::FAULT_ACTION_DELAY:
      return "delay";
    default:
      return "unknown";
  }
}

DiagnosticValues diagnostic_from_event(const msgs::FaultEvent& event) {
  DiagnosticValues d;
  d.stamp_ns = event.header().capture_stamp_ns();
  d.frame_id = event.header().frame_id();
  const msgs::FaultAction action = event.state().action();
  d.level = static_cast<DiagnosticLevel>(ros2::fault_level(action_name(action)));  // one rule
  d.name = "faultline/" + event.camera();
  d.hardware_id = event.camera();
  d.message = action_name(action);
  for (int i = 0; i < event.state().faults_size(); ++i) {
    const auto& f = event.state().faults(i);
    d.message += (i == 0 ? ": " : ", ") + f.name() + "/" + std::to_string(f.severity());
  }
  d.values.emplace_back("action", action_name(action));
  d.values.emplace_back("source_seq", std::to_string(event.source_seq()));
  if (!event.sample_token().empty()) d.values.emplace_back("sample_token", event.sample_token());
  d.values.emplace_back("injector_latency_ns", std::to_string(event.state().injector_latency_ns()));
  for (int i = 0; i < event.state().faults_size(); ++i) {
    const auto& f = event.state().faults(i);
    const std::string p = "fault" + std::to_string(i) + ".";
    d.values.emplace_back(p + "name", f.name());
    d.values.emplace_back(p + "severity", std::to_string(f.severity()));
    d.values.emplace_back(p + "seed", std::to_string(f.seed()));
    if (!f.rng().empty()) d.values.emplace_back(p + "rng", f.rng());
    const std::map<std::string, double> sorted(f.params().begin(), f.params().end());
    for (const auto& [key, value] : sorted)
      d.values.emplace_back(p + key, fmt::format("{}", value));
  }
  return d;
}

}  // namespace faultline::ros2dds
