// libFuzzer target: the ROS 2 CDR reader (ros2/cdr.hpp) through every message decoder that reads
// bytes from DDS or a rosbag2 bag (ros2/messages.hpp). The first byte picks the type, the rest is
// the message. Bad input may only be refused with a Status; a message that decodes re-encodes to
// bytes that decode again to the same bytes (the decoder keeps every field it read).
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_util.hpp"
#include "ros2/messages.hpp"

namespace {

template <typename M>
void check(std::string_view bytes) {
  using namespace faultline::ros2;
  auto decoded = deserialize<M>(bytes);
  if (!decoded.is_ok()) {
    if (decoded.status().message().empty())
      faultline::fuzz::fail("a refused message has no reason");
    return;
  }
  const std::string once = serialize(decoded.value());
  auto again = deserialize<M>(once);
  if (!again.is_ok())
    faultline::fuzz::fail("a decoded message re-encodes to bytes that do not decode");
  if (serialize(again.value()) != once) faultline::fuzz::fail("re-encoding is not stable");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline::ros2;
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 8) {
    case 0:
      check<CompressedImage>(bytes);
      break;
    case 1:
      check<Image>(bytes);
      break;
    case 2:
      check<CameraInfo>(bytes);
      break;
    case 3:
      check<TFMessage>(bytes);
      break;
    case 4:
      check<DiagnosticArray>(bytes);
      break;
    case 5:
      check<MarkerArray>(bytes);
      break;
    case 6:
      check<TransformStamped>(bytes);
      break;
    default:
      check<Header>(bytes);
      break;
  }
  return 0;
}
