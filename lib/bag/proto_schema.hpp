// Protobuf profile helpers: the serialized FileDescriptorSet (message file + all transitive
// imports, like `protoc --include_imports`) that MCAP stores as a protobuf schema's data.
#pragma once

#include <google/protobuf/descriptor.h>

#include <string>

namespace faultline::bag {

// Files ordered dependencies-first, each once. Thread-safe (reads the generated pool only).
std::string build_file_descriptor_set(const google::protobuf::Descriptor* descriptor);

}  // namespace faultline::bag
