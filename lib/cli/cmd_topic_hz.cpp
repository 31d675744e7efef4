// `faultline topic hz TOPIC`: message rate from receive times over a sliding window. Also defines
// run_probe_command(), shared with `topic bw` and `topic delay`.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/access_options.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "cli/topic_tools.hpp"
#include "common/shutdown.hpp"
#include "stats/topic_meter.hpp"
#include "transport/message_text.hpp"
#include "transport/subscriber.hpp"

namespace faultline::cli {
namespace topic {

ExitStatus run_probe_command(int argc, char** argv, ProbeKind kind) {
  const char* what =
      kind == ProbeKind::Hz ? "Measure a topic's message rate from receive times."
      : kind == ProbeKind::Bw
          ? "Measure a topic's bandwidth (all frames, payload included)."
          : "Measure message age: receive time (realtime) - header.capture_stamp_ns.";
  CLI::App app{what, argv[0]};
  std::string topic_name;
  std::vector<std::string> endpoints;
  double window_s = 1.0, every_s = 1.0, duration_s = 0;
  std::uint64_t max_messages = 0;
  int hwm = 8;
  std::string stamp = "capture";
  app.add_option("topic", topic_name, "topic name")->required();
  app.add_option("--endpoint", endpoints, "bypass the registry: connect here");
  app.add_option("--window", window_s, "sliding window of the periodic lines, seconds")
      ->check(CLI::PositiveNumber);
  app.add_option("--every", every_s, "seconds between periodic lines; 0 = summary only")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--duration", duration_s, "exit after S seconds")->check(CLI::NonNegativeNumber);
  app.add_option("-n,--count", max_messages, "exit after N messages");
  app.add_option("--hwm", hwm, "receive queue depth (messages)")->check(CLI::Range(1, 1000));
  if (kind == ProbeKind::Delay) {
    app.add_option("--stamp", stamp,
                   "header stamp to age against: capture (dataset time on replays) or publish")
        ->check(CLI::IsMember({"capture", "publish"}));
  }
  transport::AccessConfig access;
  add_access_options(app, access, SocketSides::Connect);
  app.footer("Ends on Ctrl-C, --duration or -n and prints one `summary key=value ...` line.");
  FAULTLINE_PARSE(app, argc, argv);

  const Target target = resolve(topic_name, endpoints, "");
  transport::SubscriberConfig sc;
  sc.endpoints = target.endpoints;
  sc.topics = {target.topic};
  sc.rcv_hwm = hwm;
  sc.access = access;
  transport::RawSubscriber sub(sc);

  // Per message: a receive stamp and a size (and the small header parse for delay). The payload
  // stays in its zmq frame and is released when `r` goes out of scope.
  const stats::ProbeReceive receive = [&](DurationNs timeout_ns) -> Result<stats::ProbeSample> {
    auto r = sub.receive(timeout_ns);
    if (!r.is_ok()) return r.status();
    if (r->topic() != target.topic)
      return Status{StatusCode::kWouldBlock, "other topic"};  // prefix match
    stats::ProbeSample s{r->receive_mono_ns(), r->size_bytes(), stats::kNoDelay};
    if (kind == ProbeKind::Delay) {
      msgs::Header h;
      const bool ok = transport::extract_header(r->header(), &h);
      const StampNs sent = stamp == "publish" ? h.publish_stamp_ns() : h.capture_stamp_ns();
      if (ok && sent > 0) s.delay_ns = r->receive_realtime_ns() - sent;
    }
    return s;
  };
  stats::ProbeOptions options;
  options.window_ns = static_cast<DurationNs>(window_s * 1e9);
  options.report_every_ns = static_cast<DurationNs>(every_s * 1e9);
  options.duration_ns = static_cast<DurationNs>(duration_s * 1e9);
  options.max_messages = max_messages;
  const auto report = [kind](const stats::MeterStats& w) {
    const std::string line = kind == ProbeKind::Hz   ? stats::format_hz(w)
                             : kind == ProbeKind::Bw ? stats::format_bw(w)
                                                     : stats::format_delay(w);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  };
  const stats::ProbeResult result =
      stats::run_probe(receive, options, shutdown_requested(), report);
  std::printf("%s malformed=%llu end=\"%s\"\n",
              stats::format_summary(target.topic, result.total).c_str(),
              static_cast<unsigned long long>(sub.malformed()), stats::to_string(result.end));
  if (kind == ProbeKind::Delay && result.total.count > 0 && result.total.delay_ms.count == 0) {
    std::fprintf(stderr, "no message carried header.%s_stamp_ns\n", stamp.c_str());
  }
  // A receive error ends the probe: dispatch prints it after the summary, which scripts read.
  if (result.end == stats::ProbeEnd::ReceiveError) return failure("receive error: " + result.error);
  return result.total.count > 0 ? 0 : kExitFailure;
}

}  // namespace topic

namespace {
ExitStatus run(int argc, char** argv) {
  return topic::run_probe_command(argc, argv, topic::ProbeKind::Hz);
}
}  // namespace
FAULTLINE_COMMAND(topic_hz, "topic hz",
                  "rate of a topic from receive times (min/max/std of period)", &run);
}  // namespace faultline::cli
