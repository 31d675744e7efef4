#include "runtime/bag_layout.hpp"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include "header.pb.h"

namespace faultline::runtime {

std::string multipart_prefix(std::size_t header_bytes) {
  std::string out(4, '\0');
  const auto n = static_cast<std::uint32_t>(header_bytes);
  for (int i = 0; i < 4; ++i)
    out[static_cast<std::size_t>(i)] = static_cast<char>((n >> (8 * i)) & 0xff);
  return out;
}

std::string encode_multipart(std::string_view header, std::string_view payload) {
  std::string out;
  out.reserve(4 + header.size() + payload.size());
  out.append(multipart_prefix(header.size()));
  out.append(header);
  out.append(payload);
  return out;
}

Result<MultipartView> decode_multipart(std::string_view data) {
  if (data.size() < 4)
    return {StatusCode::kCorruptData, "multipart: shorter than its length prefix"};
  std::uint32_t n = 0;
  for (int i = 0; i < 4; ++i)
    n |= static_cast<std::uint32_t>(static_cast<unsigned char>(data[i])) << (8 * i);
  if (n > data.size() - 4) {
    return {StatusCode::kCorruptData, "multipart: header length " + std::to_string(n) +
                                          " exceeds " + std::to_string(data.size() - 4) + " bytes"};
  }
  return MultipartView{data.substr(4, n), data.substr(4 + n)};
}

bool read_header_fields(std::string_view body, HeaderFields* out) {
  using google::protobuf::internal::WireFormatLite;
  google::protobuf::io::CodedInputStream in(reinterpret_cast<const std::uint8_t*>(body.data()),
                                            static_cast<int>(body.size()));
  while (true) {
    const std::uint32_t tag = in.ReadTag();
    if (tag == 0) return false;
    if (WireFormatLite::GetTagFieldNumber(tag) == 1 &&
        WireFormatLite::GetTagWireType(tag) == WireFormatLite::WIRETYPE_LENGTH_DELIMITED) {
      std::uint32_t len = 0;
      const void* data = nullptr;
      int size = 0;
      if (!in.ReadVarint32(&len) || !in.GetDirectBufferPointer(&data, &size) ||
          static_cast<std::uint32_t>(size) < len) {
        return false;
      }
      msgs::Header h;
      if (!h.ParseFromArray(data, static_cast<int>(len))) return false;
      out->seq = h.seq();
      out->publish_stamp_ns = h.publish_stamp_ns();
      out->publisher = h.publisher();
      return true;
    }
    if (!WireFormatLite::SkipField(&in, tag)) return false;
  }
}

std::string sibling_camera_info_topic(const std::string& image_topic) {
  const auto slash = image_topic.rfind('/');
  if (slash == std::string::npos) return image_topic + "/camera_info";
  return image_topic.substr(0, slash) + "/camera_info";
}

}  // namespace faultline::runtime
