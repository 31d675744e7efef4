// `faultline topic info TOPIC`: type and publishers from the registry; with --endpoint, the layout
// of the first message heard.
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

ExitStatus probe_first_message(const std::string& topic, const std::vector<std::string>& endpoints,
                               double timeout_s, const transport::AccessConfig& access) {
  transport::SubscriberConfig sc;
  sc.endpoints = endpoints;
  sc.access = access;
  sc.topics = {topic};
  transport::RawSubscriber sub(sc);
  const auto& stop = shutdown_requested();
  const StampNs deadline = monotonic_now_ns() + static_cast<DurationNs>(timeout_s * 1e9);
  while (!stop.load() && monotonic_now_ns() < deadline) {
    auto r = sub.receive(50 * kNsPerMs);
    if (r.status().code() == StatusCode::kCancelled) break;
    if (!r.is_ok() || r->topic() != topic) continue;
    msgs::Header h;
    const bool has_header = transport::extract_header(r->header(), &h);
    std::printf("Frames: %d (%s)\n", r->has_payload() ? 3 : 2,
                r->has_payload() ? "[topic][header][payload]" : "[topic][body]");
    std::printf("Header frame: %zu bytes\n", r->header().size());
    if (r->has_payload()) std::printf("Payload: %zu bytes\n", r->payload_size());
    if (has_header) {
      std::printf("Publisher: %s  frame_id: %s  seq: %" PRIu64 "\n", h.publisher().c_str(),
                  h.frame_id().c_str(), h.seq());
    }
    std::printf("summary topic=%s heard=1\n", topic.c_str());
    return 0;
  }
  std::printf("summary topic=%s heard=0\n", topic.c_str());
  char waited[32];
  std::snprintf(waited, sizeof(waited), "%.1f s", timeout_s);
  return failure("no message on " + topic + " within " + waited);
}

ExitStatus run(int argc, char** argv) {
  CLI::App app{"Show a topic's type, publishers and endpoints.", argv[0]};
  std::string topic;
  std::vector<std::string> endpoints;
  double duration_s = 2.0;
  app.add_option("topic", topic, "topic name, e.g. /cam_front/image_rect_compressed")->required();
  app.add_option("--endpoint", endpoints, "bypass the registry: listen here for one message");
  app.add_option("--duration", duration_s, "seconds to wait for a message with --endpoint")
      ->check(CLI::PositiveNumber);
  transport::AccessConfig access;
  add_access_options(app, access, SocketSides::Connect);
  FAULTLINE_PARSE(app, argc, argv);
  if (!endpoints.empty()) {
    std::printf("Topic: %s\nEndpoints: %zu\n", topic.c_str(), endpoints.size());
    return probe_first_message(topic, endpoints, duration_s, access);
  }
  std::vector<transport::TopicInfo> publishers;
  for (const auto& t : transport::list_topics()) {
    if (t.topic == topic) publishers.push_back(t);
  }
  if (publishers.empty())
    return failure("topic " + topic + ": no live publisher in the registry " +
                   transport::run_dir());
  std::printf("Topic: %s\nType: %s\nPublishers: %zu\n", topic.c_str(),
              publishers.front().type.c_str(), publishers.size());
  for (const auto& p : publishers) {
    std::printf("  %s (pid %d) at %s%s\n", p.node.c_str(), static_cast<int>(p.pid),
                p.endpoint.c_str(),
                p.type != publishers.front().type ? (" type " + p.type).c_str() : "");
  }
  std::printf("summary topic=%s publishers=%zu\n", topic.c_str(), publishers.size());
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(topic_info, "topic info", "show a topic's type, publishers and endpoints", &run);
}  // namespace faultline::cli
