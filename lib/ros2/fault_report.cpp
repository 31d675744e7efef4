#include "ros2/fault_report.hpp"

#include <charconv>
#include <cmath>
#include <utility>

namespace faultline::ros2 {

std::uint8_t fault_level(std::string_view action) {
  if (action == "pass") return DiagnosticStatus::kOk;
  if (action == "corrupt" || action == "delay") return DiagnosticStatus::kWarn;
  return DiagnosticStatus::kError;
}

std::string fault_param_text(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value < 0 ? "-inf" : "inf";
  char buf[32];
  const auto result = std::to_chars(buf, buf + sizeof buf, value);  // shortest round trip
  return std::string(buf, result.ptr);
}

ReportedFault reported_fault(std::string name, std::int64_t severity, std::uint64_t seed,
                             std::string rng, const std::map<std::string, double>& params) {
  ReportedFault f{std::move(name), severity, seed, std::move(rng), {}};
  for (const auto& [key, value] : params) f.params.push_back({key, fault_param_text(value)});
  return f;
}

DiagnosticArray to_diagnostic_array(const FaultReport& report) {
  DiagnosticArray a;
  a.header = report.header;
  DiagnosticStatus s;
  s.level = fault_level(report.action);
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
