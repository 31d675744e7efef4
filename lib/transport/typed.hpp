// Protobuf helpers on top of the byte transport: serialise a message into the header/body frame and
// parse and validate received ones. The byte core (publisher.hpp, subscriber.hpp) never sees
// protobuf.
#pragma once

#include <google/protobuf/message_lite.h>

#include <map>
#include <string>
#include <string_view>

#include "camera_frame.pb.h"
#include "common/status.hpp"
#include "transport/payload.hpp"
#include "transport/publisher.hpp"
#include "transport/shm_ring.hpp"
#include "transport/subscriber.hpp"

namespace faultline::transport {

// A validated image message: the parsed header plus the payload still inside the zmq frame.
struct CameraFrameView {
  msgs::CameraFrame header;
  const std::uint8_t* payload = nullptr;  // valid while the ReceivedMessage lives
  std::size_t payload_size = 0;
};

// Checks frame count (3), header parse, payload_size == header.payload_bytes and, for raw
// encodings, step * height == payload_size (step >= width * channels). kCorruptData naming the
// check; a shared-memory frame (header.shm set, 2 frames) is kUnsupported, naming ShmCameraReader.
Result<CameraFrameView> parse_camera_frame(const ReceivedMessage& message);

// Parses a two-part [topic][body] message into `out`; kCorruptData on a wrong frame count or bad
// bytes.
Status parse_message(const ReceivedMessage& message, google::protobuf::MessageLite* out);

// The capture stamp to age a message against: capture_stamp_ns for a wall-clock capture, else 0 (no
// age; a replay's dataset time would read as an age of years).
inline StampNs wall_clock_capture_ns(const msgs::Header& h) {
  return h.capture_clock() == msgs::CAPTURE_CLOCK_REALTIME ? h.capture_stamp_ns() : 0;
}

// Sets header.payload_bytes, serialises the header and sends [topic][header][payload].
Status send_camera_frame(Publisher& publisher, std::string_view topic, msgs::CameraFrame& header,
                         const Payload& payload);
Status send_message(Publisher& publisher, std::string_view topic,
                    const google::protobuf::MessageLite& message);

// Shared-memory output (docs/protocol.md §16): copies the payload into the next slot of `ring` and
// sends [topic][header] with header.shm and payload_bytes set. kInvalidArgument when the payload is
// larger than a slot (refused, counted by the ring, nothing sent). Publishing thread only (the ring
// has one writer).
Status send_camera_frame_shm(Publisher& publisher, ShmRingWriter& ring, std::string_view topic,
                             msgs::CameraFrame& header, const Payload& payload);

// Receiving side of shared-memory frames, for C++ subscribers: maps each publisher's ring on first
// use (and again when the publisher restarted with a new ring) and checks descriptors like
// parse_camera_frame checks payloads. One thread.
class ShmCameraReader {
 public:
  // A [topic][CameraFrame] message with header.shm set: the view's payload points into the ring, no
  // copy. Use the bytes, then call intact(): false means they were overwritten meanwhile.
  // kNotFound: the frame was overwritten before it was read (counted in overwritten()) or the ring
  // file is gone; kCorruptData naming the check.
  Result<CameraFrameView> read(const ReceivedMessage& message);
  // The slot still holds the frame of `view` (a view from read()); false is counted in
  // overwritten().
  bool intact(const CameraFrameView& view);
  // Frames lost to overwriting: before they were read plus while in use.
  std::uint64_t overwritten() const;

 private:
  Result<ShmRingReader*> ring_for(const msgs::ShmSlot& shm);
  std::map<std::string, ShmRingReader> rings_;  // path -> mapping
  std::uint64_t lost_in_closed_rings_ = 0;  // counts of mappings replaced after a publisher restart
};

// Bytes per pixel of a raw encoding ("bgr8" 3, "mono8" 1, ...); 0 for "jpeg" or unknown.
int bytes_per_pixel(const std::string& encoding);

}  // namespace faultline::transport
