#include "ros2/fault_report.hpp"

namespace faultline::ros2 {

DiagnosticArray to_diagnostic_array(const FaultReport& report) {
  DiagnosticArray a;
  a.header = report.header;
  DiagnosticStatus s;
  s.level = report.level;
  s.name = report.name;
  s.hardware_id = report.hardware_id;
  s.message = report.action;
  for (const auto& f : report.faults) s.message += " " + f.name + "/" + std::to_string(f.severity);
  if (!report.why.empty()) s.message += ": " + report.why;
  s.values = report.values;
  for (const auto& f : report.faults) {
    s.values.push_back({f.name + ".severity", std::to_string(f.severity)});
    s.values.push_back({f.name + ".seed", std::to_string(f.seed)});
    s.values.push_back({f.name + ".rng", f.rng});
    for (const auto& p : f.params) s.values.push_back({f.name + "." + p.key, p.value});
  }
  a.status.push_back(std::move(s));
  return a;
}

}  // namespace faultline::ros2
