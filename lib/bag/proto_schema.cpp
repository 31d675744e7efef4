// Walks FileDescriptor::dependency() depth-first so every import precedes its users.
#include "bag/proto_schema.hpp"

#include <google/protobuf/descriptor.pb.h>

#include <set>

namespace faultline::bag {

namespace {
void add_file(const google::protobuf::FileDescriptor* file, std::set<std::string>& seen,
              google::protobuf::FileDescriptorSet& set) {
  if (!seen.insert(file->name()).second) return;
  for (int i = 0; i < file->dependency_count(); ++i) add_file(file->dependency(i), seen, set);
  file->CopyTo(set.add_file());
}
}  // namespace

std::string build_file_descriptor_set(const google::protobuf::Descriptor* descriptor) {
  google::protobuf::FileDescriptorSet set;
  std::set<std::string> seen;
  add_file(descriptor->file(), seen, set);
  return set.SerializeAsString();
}

}  // namespace faultline::bag
