#include "transport/message_text.hpp"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/dynamic_message.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/text_format.h>
#include <google/protobuf/wire_format_lite.h>

#include <cinttypes>
#include <cstdio>
#include <map>
#include <memory>

#include "camera_frame.pb.h"
#include "common/hash.hpp"
#include "detection.pb.h"
#include "fault.pb.h"
#include "stats.pb.h"

namespace faultline::transport {

namespace pb = google::protobuf;

bool extract_header(std::string_view bytes, msgs::Header* header) {
  using pb::internal::WireFormatLite;
  pb::io::CodedInputStream in(reinterpret_cast<const std::uint8_t*>(bytes.data()),
                              static_cast<int>(bytes.size()));
  while (const std::uint32_t tag = in.ReadTag()) {
    if (WireFormatLite::GetTagFieldNumber(tag) == 1 &&
        WireFormatLite::GetTagWireType(tag) == WireFormatLite::WIRETYPE_LENGTH_DELIMITED) {
      std::uint32_t length = 0;
      std::string field;
      if (!in.ReadVarint32(&length) || !in.ReadString(&field, static_cast<int>(length)))
        return false;
      return header->ParseFromString(field);
    }
    if (!WireFormatLite::SkipField(&in, tag)) return false;
  }
  return false;
}

std::uint64_t payload_digest(const void* data, std::size_t size) {
  return fnv1a64(data, size, kFnv1a64LegacyBasis);  // the digests earlier versions printed
}

namespace {

class BytesAsLengthAndHash : public pb::TextFormat::FastFieldValuePrinter {
 public:
  void PrintBytes(const std::string& value, pb::TextFormat::BaseTextGenerator* out) const override {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "<%zu bytes, fnv1a64 %016" PRIx64 ">", value.size(),
                  payload_digest(value.data(), value.size()));
    out->PrintString(buf);
  }
};

// Referencing the default instances links their descriptors into the generated pool.
const pb::Message* prototype_of(const std::string& type) {
  static const std::map<std::string, const pb::Message*> known = [] {
    std::map<std::string, const pb::Message*> m;
    for (const pb::Message* p : std::initializer_list<const pb::Message*>{
             &msgs::CameraFrame::default_instance(), &msgs::SampleBoundary::default_instance(),
             &msgs::DetectionArray::default_instance(), &msgs::SampleAck::default_instance(),
             &msgs::FaultState::default_instance(), &msgs::FaultEvent::default_instance(),
             &msgs::TopicStats::default_instance(), &msgs::Header::default_instance()}) {
      m[p->GetDescriptor()->full_name()] = p;
    }
    return m;
  }();
  if (const auto it = known.find(type); it != known.end()) return it->second;
  const pb::Descriptor* d = pb::DescriptorPool::generated_pool()->FindMessageTypeByName(type);
  return d ? pb::MessageFactory::generated_factory()->GetPrototype(d) : nullptr;
}

}  // namespace

std::string message_to_text(const std::string& type, std::string_view bytes) {
  const pb::Message* prototype = prototype_of(type);
  if (!prototype) return "";
  std::unique_ptr<pb::Message> msg(prototype->New());
  if (!msg->ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) return "";
  pb::TextFormat::Printer printer;
  printer.SetDefaultFieldValuePrinter(new BytesAsLengthAndHash());  // the printer takes ownership
  std::string text;
  printer.PrintToString(*msg, &text);
  return text;
}

}  // namespace faultline::transport
