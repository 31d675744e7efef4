// Any Faultline message seen from outside its type: its Header pulled out of the serialized bytes,
// and its text form for `faultline topic echo` (bytes fields shown as length + digest). The
// `topic` commands use these on whatever a socket carries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "header.pb.h"

namespace faultline::transport {

// Parses field 1 (`Header header = 1`, first field of every Faultline message) out of serialized
// bytes without knowing the message type. False when absent or malformed.
bool extract_header(std::string_view message_bytes, msgs::Header* header);

// The digest `topic echo` shows for payloads and bytes fields: common/hash.hpp's FNV-1a-64 with
// kFnv1a64LegacyBasis (the digests earlier versions printed, which users compare across runs).
std::uint64_t payload_digest(const void* data, std::size_t size);

// Text form of a serialized message of a known type (fully qualified protobuf name); `bytes` fields
// are shown as length + payload_digest. Empty when the type is unknown or the bytes do not parse.
std::string message_to_text(const std::string& type, std::string_view bytes);

}  // namespace faultline::transport
