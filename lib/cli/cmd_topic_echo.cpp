// `faultline topic echo TOPIC`: prints each message decoded as text; payloads and `bytes` fields
// are shown as length + hash, never dumped.
#include <CLI/CLI.hpp>
#include <cinttypes>
#include <cstdio>

#include "cli/access_options.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "cli/topic_tools.hpp"
#include "common/shutdown.hpp"
#include "transport/message_text.hpp"
#include "transport/subscriber.hpp"

namespace faultline::cli {
namespace {

constexpr const char* kCameraFrameType = "faultline.msgs.CameraFrame";

void print_message(const transport::ReceivedMessage& m, const std::string& type) {
  std::printf("--- %.*s\n", static_cast<int>(m.topic().size()), m.topic().data());
  // An image message's header frame is a CameraFrame whatever the registry says about the topic.
  const std::string effective = m.has_payload() && type.empty() ? kCameraFrameType : type;
  std::string text = effective.empty() ? "" : transport::message_to_text(effective, m.header());
  if (text.empty()) {
    msgs::Header h;
    if (transport::extract_header(m.header(), &h))
      text = transport::message_to_text("faultline.msgs.Header", h.SerializeAsString());
    std::printf(
        "(%s; body %zu bytes; header only)\n",
        effective.empty() ? "type unknown, pass --type" : ("cannot decode as " + effective).c_str(),
        m.header().size());
    if (!text.empty()) std::printf("header {\n%s}\n", text.c_str());
  } else {
    std::fputs(text.c_str(), stdout);
  }
  if (m.has_payload()) {
    std::printf("payload: <%zu bytes, fnv1a64 %016" PRIx64 ">\n", m.payload_size(),
                transport::payload_digest(m.payload_data(), m.payload_size()));
  }
  std::fflush(stdout);
}

int run(int argc, char** argv) {
  CLI::App app{"Print a topic's messages as text (payloads as length + hash).", argv[0]};
  std::string topic_name, type;
  std::vector<std::string> endpoints;
  std::uint64_t max_messages = 0;
  double duration_s = 0;
  app.add_option("topic", topic_name, "topic name")->required();
  app.add_option("--endpoint", endpoints, "bypass the registry: connect here");
  app.add_option("--type", type, "protobuf type of the body (default: from the registry)");
  app.add_option("-n,--count", max_messages, "exit after N messages");
  app.add_option("--duration", duration_s, "exit after S seconds")->check(CLI::NonNegativeNumber);
  transport::AccessConfig access;
  add_access_options(app, access, SocketSides::Connect);
  FAULTLINE_PARSE(app, argc, argv);

  const topic::Target target = topic::resolve(topic_name, endpoints, type);
  transport::SubscriberConfig sc;
  sc.endpoints = target.endpoints;
  sc.topics = {target.topic};
  sc.access = access;
  transport::RawSubscriber sub(sc);
  const auto& stop = shutdown_requested();
  const StampNs start = monotonic_now_ns();
  std::uint64_t count = 0;
  while (!stop.load()) {
    if (duration_s > 0 && monotonic_now_ns() - start >= static_cast<DurationNs>(duration_s * 1e9))
      break;
    auto r = sub.receive(50 * kNsPerMs);
    if (r.status().code() == StatusCode::kCancelled) break;
    if (!r.is_ok() || r->topic() != target.topic) continue;  // a prefix match of another topic
    print_message(*r, target.type);
    if (++count == max_messages) break;
  }
  std::printf("summary topic=%s count=%" PRIu64 " malformed=%" PRIu64 "\n", target.topic.c_str(),
              count, sub.malformed());
  return count > 0 ? 0 : 1;
}

}  // namespace
FAULTLINE_COMMAND(topic_echo, "topic echo",
                  "print a topic's messages (decoded header, payload hash)", &run);
}  // namespace faultline::cli
