// Shared pieces of the `faultline topic ...` commands: finding a topic's endpoints in the registry,
// and the probe commands (hz, bw, delay). Definitions live in cmd_topic_list.cpp (registry) and
// cmd_topic_hz.cpp (probe commands), because lib/cli compiles only cmd_*.cpp files. A message's
// Header and text form come from transport/message_text.hpp.
#pragma once

#include <string>
#include <vector>

#include "cli/command.hpp"
#include "transport/registry.hpp"

namespace faultline::cli::topic {

struct Target {
  std::string topic;
  std::string type;                    // from the registry; "" with --endpoint and no --type
  std::vector<std::string> endpoints;  // where to connect
};

// --endpoint given: use it. Otherwise every publisher of `topic` in the registry; ConfigError
// naming the topic and the registry dir when there is none.
Target resolve(const std::string& topic, const std::vector<std::string>& endpoints,
               const std::string& type);

enum class ProbeKind { Hz, Bw, Delay };
// Returns the receive error, if one ended the probe, for dispatch to print after the summary.
ExitStatus run_probe_command(int argc, char** argv, ProbeKind kind);

}  // namespace faultline::cli::topic
