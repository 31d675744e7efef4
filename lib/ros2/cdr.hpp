// Classic CDR (XCDR1, little endian) as ROS 2 puts it on the DDS wire and into rosbag2 files: a
// 4-byte encapsulation header `00 01 00 00` (CDR_LE), then the body, each primitive aligned to its
// size counted from the first byte after the header. Strings: uint32 length counting the
// terminating NUL, the bytes, the NUL. Sequences: uint32 element count, then the elements (aligned
// to their own size). Fixed arrays: no count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "common/status.hpp"

namespace faultline::ros2 {

inline constexpr std::size_t kEncapsulationBytes = 4;
inline constexpr std::string_view kCdrLeHeader{"\x00\x01\x00\x00", 4};

// Appends a CDR_LE message to a string it owns. Never fails; one writer per message.
class CdrWriter {
 public:
  CdrWriter();  // starts with the encapsulation header
  void u8(std::uint8_t v) { buf_.push_back(static_cast<char>(v)); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void u32(std::uint32_t v) { put(v, 4); }
  void u64(std::uint64_t v) { put(v, 8); }
  void f32(float v);
  void f64(double v);
  void string(std::string_view s);                 // length (with NUL) + bytes + NUL
  void sequence_count(std::size_t count);          // uint32; the caller writes the elements
  void octets(std::string_view bytes);             // uint8[]: count + bytes
  void f64_array(const double* v, std::size_t n);  // fixed array: no count
  void f64_sequence(const double* v, std::size_t n);

  std::size_t size() const { return buf_.size(); }  // bytes so far, header included
  const std::string& data() const { return buf_; }
  std::string take() { return std::move(buf_); }

 private:
  void align(std::size_t n);
  void put(std::uint64_t v, int n);
  std::string buf_;
};

// Bounds-checked reader over a CDR_LE message (not owned; keep it alive). Errors are sticky: the
// first failure (truncation, a length or count that does not fit the bytes left, a string without
// its NUL) is kept with the field name and byte offset, later reads return zeros, and status()
// reports it. Nothing is allocated from a length before it is checked against the bytes that are
// actually there. Byte offsets in errors count from the start of the message (encapsulation header
// included).
class CdrReader {
 public:
  // Checks the encapsulation header: kTruncated below 4 bytes, kUnsupported for big-endian or
  // XCDR2. `type_name` prefixes every error ("sensor_msgs/msg/Image: ...").
  CdrReader(std::string_view message, std::string type_name);

  std::uint8_t u8(const char* field);
  bool boolean(const char* field) { return u8(field) != 0; }
  std::int32_t i32(const char* field) { return static_cast<std::int32_t>(u32(field)); }
  std::uint32_t u32(const char* field);
  std::uint64_t u64(const char* field);
  float f32(const char* field);
  double f64(const char* field);
  std::string string(const char* field);
  // uint32 count, rejected unless count * min_element_bytes fits in what is left.
  std::uint32_t sequence_count(const char* field, std::size_t min_element_bytes);
  std::string octets(const char* field);            // uint8[]
  std::string_view octets_view(const char* field);  // uint8[] without a copy (valid with the input)
  void f64_array(const char* field, double* out, std::size_t n);

  bool ok() const { return status_.is_ok(); }
  const Status& status() const { return status_; }
  std::size_t offset() const { return pos_; }  // bytes consumed, header included
  std::size_t remaining() const { return ok() ? in_.size() - pos_ : 0; }
  // Marks the reader failed (first error wins), e.g. for an out-of-range enum.
  void fail(StatusCode code, const char* field, const std::string& why);

 private:
  void fail_at(std::size_t at, StatusCode code, const char* field, const std::string& why);
  bool align(std::size_t n, const char* field);
  bool need(std::size_t n, const char* field);
  std::uint64_t get(int n, const char* field);
  std::string_view in_;
  std::string type_name_;
  std::size_t pos_ = kEncapsulationBytes;
  Status status_;
};

}  // namespace faultline::ros2
