// libFuzzer target: rosbag2's metadata.yaml (bag/rosbag2.hpp, read by `bag info`, `bag play` and
// `bag corrupt` for ROS 2 bag directories). Bad input may only be refused with a Status naming the
// file; what is accepted is written back as Faultline writes metadata.yaml and must read back the
// same.
#include <cstddef>
#include <cstdint>
#include <string>

#include "bag/rosbag2.hpp"
#include "fuzz_util.hpp"

namespace {

bool same(const faultline::bag::Rosbag2Metadata& a, const faultline::bag::Rosbag2Metadata& b) {
  if (a.version != b.version || a.storage_identifier != b.storage_identifier ||
      a.starting_time_ns != b.starting_time_ns || a.duration_ns != b.duration_ns ||
      a.message_count != b.message_count || a.relative_file_paths != b.relative_file_paths ||
      a.topics.size() != b.topics.size() || a.files.size() != b.files.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.topics.size(); ++i) {
    const auto& x = a.topics[i];
    const auto& y = b.topics[i];
    if (x.name != y.name || x.type != y.type || x.serialization_format != y.serialization_format ||
        x.offered_qos_profiles != y.offered_qos_profiles || x.message_count != y.message_count) {
      return false;
    }
  }
  for (std::size_t i = 0; i < a.files.size(); ++i) {
    const auto& x = a.files[i];
    const auto& y = b.files[i];
    if (x.path != y.path || x.starting_time_ns != y.starting_time_ns ||
        x.duration_ns != y.duration_ns || x.message_count != y.message_count) {
      return false;
    }
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline;
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::run_with_small_stack([&] {
    auto m = bag::parse_rosbag2_metadata(text, "bag/metadata.yaml");
    if (!m.is_ok()) {
      if (m.status().message().rfind("bag/metadata.yaml: ", 0) != 0)
        fuzz::fail("error does not name the file");
      return;
    }
    const std::string written = bag::rosbag2_metadata_yaml(m.value());
    auto back = bag::parse_rosbag2_metadata(written, "written/metadata.yaml");
    if (!back.is_ok()) fuzz::fail("metadata.yaml as written does not read back");
    if (!same(m.value(), back.value())) fuzz::fail("metadata.yaml does not read back the same");
  });
  return 0;
}
