// CDR_LE writer and bounds-checked reader.
#include "ros2/cdr.hpp"

#include <cstdio>
#include <cstring>

namespace faultline::ros2 {

CdrWriter::CdrWriter() { buf_.assign(kCdrLeHeader.data(), kCdrLeHeader.size()); }

void CdrWriter::align(std::size_t n) {
  const std::size_t body = buf_.size() - kEncapsulationBytes;
  const std::size_t pad = (n - body % n) % n;
  buf_.append(pad, '\0');
}

void CdrWriter::put(std::uint64_t v, int n) {
  align(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) buf_.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

void CdrWriter::f32(float v) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, 4);
  put(bits, 4);
}

void CdrWriter::f64(double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, 8);
  put(bits, 8);
}

void CdrWriter::string(std::string_view s) {
  u32(static_cast<std::uint32_t>(s.size() + 1));
  buf_.append(s.data(), s.size());
  buf_.push_back('\0');
}

void CdrWriter::sequence_count(std::size_t count) { u32(static_cast<std::uint32_t>(count)); }

void CdrWriter::octets(std::string_view bytes) {
  sequence_count(bytes.size());
  buf_.append(bytes.data(), bytes.size());
}

void CdrWriter::f64_array(const double* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) f64(v[i]);
}

void CdrWriter::f64_sequence(const double* v, std::size_t n) {
  sequence_count(n);
  f64_array(v, n);
}

CdrReader::CdrReader(std::string_view message, std::string type_name)
    : in_(message), type_name_(std::move(type_name)) {
  if (in_.size() < kEncapsulationBytes) {
    status_ = Status(StatusCode::kTruncated,
                     type_name_ + ": " + std::to_string(in_.size()) +
                         " bytes, shorter than the 4-byte CDR encapsulation header");
    return;
  }
  const auto b0 = static_cast<unsigned char>(in_[0]), b1 = static_cast<unsigned char>(in_[1]);
  if (b0 != 0x00 || b1 != 0x01) {
    char buf[8];
    std::snprintf(buf, sizeof(buf), "%02x %02x", b0, b1);
    status_ = Status(StatusCode::kUnsupported,
                     type_name_ + ": encapsulation " + buf +
                         ": only CDR_LE (00 01, classic little-endian CDR) is read");
  }
}

void CdrReader::fail(StatusCode code, const char* field, const std::string& why) {
  fail_at(pos_, code, field, why);
}

void CdrReader::fail_at(std::size_t at, StatusCode code, const char* field,
                        const std::string& why) {
  if (!status_.is_ok()) return;
  status_ =
      Status(code, type_name_ + ": field " + field + " at byte " + std::to_string(at) + ": " + why);
}

bool CdrReader::need(std::size_t n, const char* field) {
  if (!status_.is_ok()) return false;
  if (in_.size() - pos_ < n) {
    fail(StatusCode::kTruncated, field,
         "needs " + std::to_string(n) + " bytes, " + std::to_string(in_.size() - pos_) + " left");
    return false;
  }
  return true;
}

bool CdrReader::align(std::size_t n, const char* field) {
  if (!status_.is_ok()) return false;
  const std::size_t body = pos_ - kEncapsulationBytes;
  const std::size_t pad = (n - body % n) % n;
  if (!need(pad, field)) return false;
  pos_ += pad;
  return true;
}

std::uint64_t CdrReader::get(int n, const char* field) {
  const auto size = static_cast<std::size_t>(n);
  if (!align(size, field) || !need(size, field)) return 0;
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) {
    v |= static_cast<std::uint64_t>(
             static_cast<unsigned char>(in_[pos_ + static_cast<std::size_t>(i)]))
         << (8 * i);
  }
  pos_ += size;
  return v;
}

std::uint8_t CdrReader::u8(const char* field) { return static_cast<std::uint8_t>(get(1, field)); }
std::uint32_t CdrReader::u32(const char* field) {
  return static_cast<std::uint32_t>(get(4, field));
}
std::uint64_t CdrReader::u64(const char* field) { return get(8, field); }

float CdrReader::f32(const char* field) {
  const auto bits = static_cast<std::uint32_t>(get(4, field));
  float v = 0;
  std::memcpy(&v, &bits, 4);
  return v;
}

double CdrReader::f64(const char* field) {
  const std::uint64_t bits = get(8, field);
  double v = 0;
  std::memcpy(&v, &bits, 8);
  return v;
}

std::string CdrReader::string(const char* field) {
  const std::uint32_t length = u32(field);
  if (!ok() || length == 0) return {};  // 0: an empty string from a writer that omits the NUL
  if (!need(length, field)) return {};
  if (in_[pos_ + length - 1] != '\0') {
    fail(StatusCode::kCorruptData, field,
         "string of length " + std::to_string(length) + " lacks its NUL");
    return {};
  }
  std::string out(in_.substr(pos_, length - 1));
  pos_ += length;
  return out;
}

std::uint32_t CdrReader::sequence_count(const char* field, std::size_t min_element_bytes) {
  const std::uint32_t count = u32(field);
  if (!ok()) return 0;
  const std::size_t left = in_.size() - pos_;
  if (min_element_bytes > 0 && count > left / min_element_bytes) {
    fail_at(pos_ - 4, StatusCode::kCorruptData, field,
            "count " + std::to_string(count) + " x " + std::to_string(min_element_bytes) +
                " bytes exceeds the " + std::to_string(left) + " bytes left");
    return 0;
  }
  return count;
}

std::string_view CdrReader::octets_view(const char* field) {
  const std::uint32_t count = sequence_count(field, 1);
  if (!ok()) return {};
  std::string_view out = in_.substr(pos_, count);
  pos_ += count;
  return out;
}

std::string CdrReader::octets(const char* field) { return std::string(octets_view(field)); }

void CdrReader::f64_array(const char* field, double* out, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out[i] = f64(field);
}

}  // namespace faultline::ros2
