#include "transport/typed.hpp"

#include "deterministic_serialize.hpp"

namespace faultline::transport {

int bytes_per_pixel(const std::string& encoding) {
  if (encoding == "bgr8" || encoding == "rgb8") return 3;
  if (encoding == "bgra8" || encoding == "rgba8") return 4;
  if (encoding == "mono8") return 1;
  if (encoding == "mono16" || encoding == "yuv422" || encoding == "yuv422_yuy2") return 2;
  return 0;
}

namespace {

// The size checks shared by ZeroMQ and shared-memory payloads.
Status check_payload(const CameraFrameView& view) {
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
  return Status::ok();
}

ShmSlotRef slot_ref(const msgs::CameraFrame& h) {
  ShmSlotRef ref;
  ref.ring_id = h.shm().ring_id();
  ref.slot = h.shm().slot();
  ref.sequence = h.shm().sequence();
  ref.offset = h.shm().offset();
  ref.size_bytes = h.payload_bytes();
  return ref;
}

}  // namespace

Result<CameraFrameView> parse_camera_frame(const ReceivedMessage& message) {
  CameraFrameView view;
  const std::string_view h = message.header();
  if (!message.has_payload()) {
    if (view.header.ParseFromArray(h.data(), static_cast<int>(h.size())) && view.header.has_shm()) {
      return Status{StatusCode::kUnsupported,
                    "frame pixels are in shared memory (" + view.header.shm().path() +
                        "): read it with transport::ShmCameraReader (docs/protocol.md §16)"};
    }
    return Status{StatusCode::kCorruptData,
                  "image message needs 3 frames [topic][header][payload]"};
  }
  if (!view.header.ParseFromArray(h.data(), static_cast<int>(h.size()))) {
    return Status{StatusCode::kCorruptData, "CameraFrame header does not parse"};
  }
  view.payload = message.payload_data();
  view.payload_size = message.payload_size();
  if (Status s = check_payload(view); !s.is_ok()) return s;
  return view;
}

Status send_camera_frame_shm(Publisher& publisher, ShmRingWriter& ring, std::string_view topic,
                             msgs::CameraFrame& header, const Payload& payload) {
  auto ref = ring.write(payload.data, payload.size_bytes);
  if (!ref) return ref.status();
  header.set_payload_bytes(static_cast<std::uint32_t>(payload.size_bytes));
  msgs::ShmSlot* shm = header.mutable_shm();
  shm->set_path(ring.path());
  shm->set_ring_id(ref->ring_id);
  shm->set_slot(ref->slot);
  shm->set_sequence(ref->sequence);
  shm->set_offset(ref->offset);
  const std::string bytes = msgs::serialize_deterministic(header);
  header.clear_shm();  // the caller's header stays a plain frame (delay queues, retries)
  return publisher.send(topic, bytes);
}

Result<ShmRingReader*> ShmCameraReader::ring_for(const msgs::ShmSlot& shm) {
  auto it = rings_.find(shm.path());
  if (it != rings_.end() && it->second.ring_id() == shm.ring_id()) return &it->second;
  auto opened = ShmRingReader::open(shm.path());
  if (!opened) return opened.status();
  if (it != rings_.end()) {  // the publisher restarted: a new file at the same path
    lost_in_closed_rings_ +=
        it->second.overwritten_before_read() + it->second.overwritten_during_use();
    it->second = std::move(opened).value();
    return &it->second;
  }
  return &rings_.emplace(shm.path(), std::move(opened).value()).first->second;
}

Result<CameraFrameView> ShmCameraReader::read(const ReceivedMessage& message) {
  CameraFrameView view;
  const std::string_view h = message.header();
  if (message.has_payload())
    return Status{StatusCode::kCorruptData, "shm frame needs 2 frames [topic][header]"};
  if (!view.header.ParseFromArray(h.data(), static_cast<int>(h.size()))) {
    return Status{StatusCode::kCorruptData, "CameraFrame header does not parse"};
  }
  if (!view.header.has_shm())
    return Status{StatusCode::kCorruptData, "2-frame image message without shm slot"};
  auto ring = ring_for(view.header.shm());
  if (!ring) return ring.status();
  auto slot = (*ring)->acquire(slot_ref(view.header));
  if (!slot) return slot.status();
  view.payload = slot->data;
  view.payload_size = slot->size_bytes;
  if (Status s = check_payload(view); !s.is_ok()) return s;
  return view;
}

bool ShmCameraReader::intact(const CameraFrameView& view) {
  auto it = rings_.find(view.header.shm().path());
  if (it == rings_.end()) return false;
  ShmFrameView slot;
  slot.data = view.payload;
  slot.size_bytes = view.payload_size;
  slot.ref = slot_ref(view.header);
  return it->second.intact(slot);
}

std::uint64_t ShmCameraReader::overwritten() const {
  std::uint64_t n = lost_in_closed_rings_;
  for (const auto& [path, ring] : rings_)
    n += ring.overwritten_before_read() + ring.overwritten_during_use();
  return n;
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
  const std::string bytes = msgs::serialize_deterministic(header);
  return publisher.send(topic, bytes, payload);
}

Status send_message(Publisher& publisher, std::string_view topic,
                    const google::protobuf::MessageLite& message) {
  const std::string bytes = msgs::serialize_deterministic(message);
  return publisher.send(topic, bytes);
}

}  // namespace faultline::transport
