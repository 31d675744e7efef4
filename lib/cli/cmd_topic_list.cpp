// `faultline topic list`: advertised topics (registry) or, with --endpoint, topics seen on a
// socket. Also holds the shared helpers declared in topic_tools.hpp.
#include <google/protobuf/descriptor.h>
#include <google/protobuf/dynamic_message.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/text_format.h>
#include <google/protobuf/wire_format_lite.h>

#include <CLI/CLI.hpp>
#include <cinttypes>
#include <cstdio>
#include <map>
#include <memory>

#include "camera_frame.pb.h"
#include "cli/access_options.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "cli/topic_tools.hpp"
#include "common/config.hpp"
#include "common/hash.hpp"
#include "common/shutdown.hpp"
#include "detection.pb.h"
#include "fault.pb.h"
#include "stats.pb.h"
#include "transport/subscriber.hpp"

namespace faultline::cli {
namespace topic {

namespace pb = google::protobuf;

Target resolve(const std::string& topic, const std::vector<std::string>& endpoints,
               const std::string& type) {
  Target t{topic, type, endpoints};
  if (!endpoints.empty()) return t;
  for (const auto& info : transport::list_topics()) {
    if (info.topic != topic) continue;
    t.endpoints.push_back(info.endpoint);
    if (t.type.empty()) t.type = info.type;
  }
  if (t.endpoints.empty()) {
    throw ConfigError("topic " + topic + ": no live publisher in the registry " +
                      transport::run_dir() + " (see `faultline topic list`, or pass --endpoint)");
  }
  return t;
}

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

std::uint64_t digest(const void* data, std::size_t size) {
  return fnv1a64(data, size, kFnv1a64LegacyBasis);  // the digests earlier versions printed
}

namespace {

class BytesAsLengthAndHash : public pb::TextFormat::FastFieldValuePrinter {
 public:
  void PrintBytes(const std::string& value, pb::TextFormat::BaseTextGenerator* out) const override {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "<%zu bytes, fnv1a64 %016" PRIx64 ">", value.size(),
                  digest(value.data(), value.size()));
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

std::string decode_to_text(const std::string& type, std::string_view bytes) {
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

}  // namespace topic

namespace {

struct Seen {
  std::uint64_t count = 0;
  std::size_t frames = 0;
  std::string publisher;
};

int list_endpoint(const std::vector<std::string>& endpoints, double duration_s,
                  const transport::AccessConfig& access) {
  transport::SubscriberConfig sc;
  sc.endpoints = endpoints;
  sc.access = access;
  sc.topics = {""};
  transport::RawSubscriber sub(sc);
  std::map<std::string, Seen> seen;
  const auto& stop = shutdown_requested();
  const StampNs deadline = monotonic_now_ns() + static_cast<DurationNs>(duration_s * 1e9);
  while (!stop.load() && monotonic_now_ns() < deadline) {
    auto r = sub.receive(50 * kNsPerMs);
    if (r.status().code() == StatusCode::kCancelled) break;
    if (!r.is_ok()) continue;
    Seen& s = seen[std::string(r->topic())];
    ++s.count;
    s.frames = r->has_payload() ? 3 : 2;
    msgs::Header h;
    if (s.publisher.empty() && topic::extract_header(r->header(), &h)) s.publisher = h.publisher();
  }
  std::printf("%-44s %-8s %-8s %s\n", "TOPIC", "FRAMES", "MSGS", "PUBLISHER");
  for (const auto& [name, s] : seen) {
    std::printf("%-44s %-8zu %-8" PRIu64 " %s\n", name.c_str(), s.frames, s.count,
                s.publisher.c_str());
  }
  std::printf("summary topics=%zu source=%s listened_s=%.1f\n", seen.size(),
              endpoints.front().c_str(), duration_s);
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"List topics: from the registry of live publishers, or heard on --endpoint.",
               argv[0]};
  std::vector<std::string> endpoints;
  double duration_s = 1.0;
  app.add_option("--endpoint", endpoints,
                 "listen on this endpoint instead of reading the registry");
  app.add_option("--duration", duration_s, "seconds to listen with --endpoint")
      ->check(CLI::PositiveNumber);
  transport::AccessConfig access;
  add_access_options(app, access, SocketSides::Connect);
  app.footer(
      "Registry: $FAULTLINE_RUN_DIR or /tmp/faultline-<uid>/graph (one file per publishing node).");
  FAULTLINE_PARSE(app, argc, argv);
  if (!endpoints.empty()) return list_endpoint(endpoints, duration_s, access);

  const auto topics = transport::list_topics();
  std::printf("%-44s %-30s %-24s %s\n", "TOPIC", "TYPE", "NODE (PID)", "ENDPOINT");
  for (const auto& t : topics) {
    const std::string node = t.node + " (" + std::to_string(t.pid) + ")";
    std::printf("%-44s %-30s %-24s %s\n", t.topic.c_str(), t.type.c_str(), node.c_str(),
                t.endpoint.c_str());
  }
  std::printf("summary topics=%zu registry=%s\n", topics.size(), transport::run_dir().c_str());
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(topic_list, "topic list", "list topics with type, publisher node and endpoint",
                  &run);
}  // namespace faultline::cli
