// libFuzzer target: fault schedules (policy/fault_spec.hpp) from arbitrary text: the `faults` list
// of an injector parameters file, and the first line as a `corruption:` shorthand. Bad input may
// only be refused with a ConfigError (text that is not YAML at all, YAML::Exception, never reaches
// the schedule parser). Every accepted fault's severity stays within 0..severity over its window.
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "common/config.hpp"
#include "fuzz_util.hpp"
#include "policy/fault_spec.hpp"

namespace {

void check(const faultline::policy::FaultSpec& spec) {
  for (const faultline::DurationNs t : {std::int64_t{0}, std::int64_t{1}, std::int64_t{999'999'999},
                                        std::int64_t{3'600'000'000'000}, INT64_MAX, INT64_MIN}) {
    const int s = faultline::policy::severity_at(spec, t);
    if (s < 0 || s > spec.severity) faultline::fuzz::fail("severity_at out of 0..severity");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto shorthand =
        policy::parse_corruption_shorthand(text.substr(0, text.find('\n')), "fault_injector");
    if (shorthand) check(*shorthand);
  } catch (const ConfigError&) {
  }
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::Exception&) {
    return 0;
  }
  try {
    const YAML::Node faults = doc.IsMap() ? doc["faults"] : doc;
    for (const auto& spec : policy::parse_faults(faults, "fault_injector")) check(spec);
  } catch (const ConfigError&) {
  }
  return 0;
}
