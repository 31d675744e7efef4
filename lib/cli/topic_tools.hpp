// Shared pieces of the `faultline topic ...` commands: finding a topic's endpoints in the registry,
// extracting the Header from any message, and decoding messages for `topic echo`.
// Definitions live in cmd_topic_list.cpp (registry, decoding) and cmd_topic_hz.cpp (probe
// commands), because lib/cli compiles only cmd_*.cpp files.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "header.pb.h"
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

// Parses field 1 (`Header header = 1`, first field of every Faultline message) out of serialized
// bytes without knowing the message type. False when absent or malformed.
bool extract_header(std::string_view message_bytes, msgs::Header* header);

// The digest `topic echo` shows for payloads and bytes fields: common/hash.hpp's FNV-1a-64 with
// kFnv1a64LegacyBasis.
std::uint64_t digest(const void* data, std::size_t size);

// Text form of a serialized message of a known type (fully qualified protobuf name); `bytes` fields
// are shown as length + hash. Empty when the type is unknown or the bytes do not parse.
std::string decode_to_text(const std::string& type, std::string_view bytes);

enum class ProbeKind { Hz, Bw, Delay };
int run_probe_command(int argc, char** argv, ProbeKind kind);

}  // namespace faultline::cli::topic
