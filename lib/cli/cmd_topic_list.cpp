// `faultline topic list`: advertised topics (registry) or, with --endpoint, topics seen on a
// socket. Also holds resolve() of topic_tools.hpp.
#include <CLI/CLI.hpp>
#include <cinttypes>
#include <cstdio>
#include <map>
#include <memory>

#include "cli/access_options.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "cli/topic_tools.hpp"
#include "common/config.hpp"
#include "common/shutdown.hpp"
#include "transport/message_text.hpp"
#include "transport/subscriber.hpp"

namespace faultline::cli {
namespace topic {

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
    if (s.publisher.empty() && transport::extract_header(r->header(), &h))
      s.publisher = h.publisher();
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
