#pragma once
// Protobuf leaves the order of map entries unspecified, so two serializations of equal messages can
// differ. Every byte Faultline writes to the wire or a bag goes through here: same seed, same
// bytes.
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/message_lite.h>

#include <string>

namespace faultline::msgs {

// Appends nothing on failure and returns false (a required field missing in a proto2 message cannot
// happen here: all of msgs/ is proto3).
inline bool serialize_deterministic(const google::protobuf::MessageLite& message,
                                    std::string* out) {
  out->clear();
  google::protobuf::io::StringOutputStream stream(out);
  google::protobuf::io::CodedOutputStream coded(&stream);
  coded.SetSerializationDeterministic(true);
  if (!message.SerializeToCodedStream(&coded)) return false;
  coded.Trim();
  return !coded.HadError();
}

inline std::string serialize_deterministic(const google::protobuf::MessageLite& message) {
  std::string out;
  serialize_deterministic(message, &out);
  return out;
}

}  // namespace faultline::msgs
