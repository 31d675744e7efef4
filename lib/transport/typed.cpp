#include "transport/typed.hpp"

namespace faultline::transport {

int bytes_per_pixel(const std::string& encoding) {
  if (encoding == "bgr8" || encoding == "rgb8") return 3;
  if (encoding == "bgra8" || encoding == "rgba8") return 4;
  if (encoding == "mono8") return 1;
  if (encoding == "mono16" || encoding == "yuv422" || encoding == "yuv422_yuy2") return 2;
  return 0;
}

Result<CameraFrameView> parse_camera_frame(const ReceivedMessage& message) {
  if (!message.has_payload()) {
    return Status{StatusCode::kCorruptData, "image message needs 3 frames [topic][header][payload]"};
  }
  CameraFrameView view;
  const std::string_view h = message.header();
  if (!view.header.ParseFromArray(h.data(), static_cast<int>(h.size()))) {
    return Status{StatusCode::kCorruptData, "CameraFrame header does not parse"};
  }
  view.payload = message.payload_data();
  view.payload_size = message.payload_size();
  if (view.header.payload_bytes() != view.payload_size) {
    return Status{StatusCode::kCorruptData, "payload is " + std::to_string(view.payload_size) +
                                                " bytes, header says payload_bytes=" +
                                                std::to_string(view.header.payload_bytes())};
  }
  if (view.header.encoding() != "jpeg") {
    const int bpp = bytes_per_pixel(view.header.encoding());
    if (bpp == 0) {
      return Status{StatusCode::kCorruptData, "unknown encoding '" + view.header.encoding() + "'"};
    }
    const std::uint64_t step = view.header.step();
    if (step < static_cast<std::uint64_t>(view.header.width()) * static_cast<std::uint64_t>(bpp) ||
        step * view.header.height() != view.payload_size) {
      return Status{StatusCode::kCorruptData,
                    "raw payload " + std::to_string(view.payload_size) + " bytes != step " +
                        std::to_string(step) + " x height " + std::to_string(view.header.height())};
    }
  }
  return view;
}

Status parse_message(const ReceivedMessage& message, google::protobuf::MessageLite* out) {
  if (message.has_payload()) {
    return {StatusCode::kCorruptData, "expected 2 frames [topic][body], got 3"};
  }
  const std::string_view body = message.header();
  if (!out->ParseFromArray(body.data(), static_cast<int>(body.size()))) {
    return {StatusCode::kCorruptData, out->GetTypeName() + " does not parse"};
  }
  return Status::ok();
}

Status send_camera_frame(Publisher& publisher, std::string_view topic, msgs::CameraFrame& header,
                         const Payload& payload) {
  header.set_payload_bytes(static_cast<std::uint32_t>(payload.size_bytes));
  const std::string bytes = header.SerializeAsString();
  return publisher.send(topic, bytes, payload);
}

Status send_message(Publisher& publisher, std::string_view topic,
                    const google::protobuf::MessageLite& message) {
  const std::string bytes = message.SerializeAsString();
  return publisher.send(topic, bytes);
}

}  // namespace faultline::transport
