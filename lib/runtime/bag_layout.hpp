// How live transport messages are stored in an MCAP bag so `bag play` can republish the exact bytes
// while Foxglove still sees viewable channels (specs/interfaces.md §3, §4.2, §4.3).
//
// Replay channels (the source of truth for `bag play`) carry channel metadata
//   faultline.topic  = the transport topic,  faultline.frames = "2" or "3",  faultline.type = proto
//   type.
// - Image messages [topic][CameraFrame][payload] go to the private channel "/faultline/raw" +
// topic,
//   message_encoding "faultline-multipart", schema faultline.msgs.CameraFrame (describes the
//   header). Message data = u32 little-endian header length, the CameraFrame bytes, then the
//   payload bytes.
// - Two-part messages [topic][body] go to a channel named by the topic itself: message_encoding
//   "protobuf" with the type's schema when the type is known, else schemaless "faultline-body".
//   The data is the body, byte for byte.
// MCAP sequence = header.seq (low 32 bits), log_time = receive time (CLOCK_REALTIME), publish_time
// = header.publish_stamp_ns. View channels (CompressedImage/RawImage on the topic,
// CameraCalibration, /tf, /detections/markers) have no faultline.frames key and are never replayed.
// Faults arrive as the injector's own /faultline/faults topic (FaultEvent) and are recorded like
// any two-part topic.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "common/status.hpp"

namespace faultline::runtime {

inline constexpr const char* kRawTopicPrefix = "/faultline/raw";
inline constexpr const char* kMultipartEncoding = "faultline-multipart";
inline constexpr const char* kBodyEncoding = "faultline-body";
inline constexpr const char* kMetaTopic = "faultline.topic";
inline constexpr const char* kMetaFrames = "faultline.frames";
inline constexpr const char* kMetaType = "faultline.type";

// u32 LE header length + header + payload.
std::string encode_multipart(std::string_view header, std::string_view payload);
// Just the 4-byte length prefix, for writing the parts without concatenating them.
std::string multipart_prefix(std::size_t header_bytes);
struct MultipartView {
  std::string_view header;
  std::string_view payload;
};
// kCorruptData when the length prefix does not fit the data.
Result<MultipartView> decode_multipart(std::string_view data);

// Reads field 1 (Header) of any Faultline message body; false when absent or malformed.
struct HeaderFields {
  std::uint64_t seq = 0;
  std::int64_t publish_stamp_ns = 0;
  std::string publisher;
};
bool read_header_fields(std::string_view body, HeaderFields* out);

// "/faulty/cam_front/image_rect_compressed" -> "/faulty/cam_front/camera_info".
std::string sibling_camera_info_topic(const std::string& image_topic);

}  // namespace faultline::runtime
