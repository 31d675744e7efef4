// libFuzzer target: the wire frame parser (transport/typed.hpp) over arbitrary received messages.
// Input layout: byte 0 bit 0 picks three frames [topic][header][payload] (set) or two
// [topic][body]; bytes 1-2 (little endian) are the header length, clipped to what is left; the
// header follows and the rest is the payload. A frame parse_camera_frame accepts must describe
// pixels inside its payload, as its consumers assume.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "camera_frame.pb.h"
#include "detection.pb.h"
#include "fault.pb.h"
#include "fuzz_util.hpp"
#include "transport/typed.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline;
  if (size < 3) return 0;
  const bool three = (data[0] & 1) != 0;
  const std::size_t header_len =
      std::min<std::size_t>(data[1] | (std::size_t{data[2]} << 8), size - 3);
  const char* bytes = reinterpret_cast<const char*>(data);
  const std::string_view header(bytes + 3, header_len);
  const std::string_view payload(bytes + 3 + header_len, size - 3 - header_len);
  std::vector<std::string_view> frames{"/cam_front/image_rect_compressed", header};
  if (three) frames.push_back(payload);
  const auto message = transport::ReceivedMessage::from_frames(frames);

  if (auto view = transport::parse_camera_frame(message)) {
    const auto& h = view->header;
    if (view->payload_size != message.payload_size())
      fuzz::fail("payload size differs from the frame's");
    const int bpp = transport::bytes_per_pixel(h.encoding());
    if (h.encoding() != "jpeg" && h.width() > 0 && h.height() > 0) {
      // Just past the last pixel byte a consumer reads, computed without overflow.
      std::uint64_t rows = 0, last = 0;
      const bool overflow =
          __builtin_mul_overflow(std::uint64_t{h.height() - 1}, std::uint64_t{h.step()}, &rows) ||
          __builtin_add_overflow(rows, std::uint64_t{h.width()} * static_cast<unsigned>(bpp),
                                 &last);
      if (bpp == 0 || overflow || last > view->payload_size) {
        fuzz::fail("accepted raw frame reaches beyond its payload");
      }
      volatile std::uint8_t touch = view->payload[static_cast<std::size_t>(last) - 1];
      (void)touch;
    }
  }
  msgs::SampleBoundary boundary;
  (void)transport::parse_message(message, &boundary);
  msgs::StreamEnd end;
  (void)transport::parse_message(message, &end);
  msgs::DetectionArray detections;
  (void)transport::parse_message(message, &detections);
  msgs::SampleAck ack;
  (void)transport::parse_message(message, &ack);
  msgs::FaultEvent event;
  (void)transport::parse_message(message, &event);
  return 0;
}
