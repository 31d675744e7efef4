// `faultline bench topic-hz`: a paced publisher thread (raw frames, absolute schedule) and the
// `topic hz` probe loop in one process; prints sent/received counts and the measured vs the
// publisher's rate, for a receiver that uses payloads in place and one that copies each payload
// (what a copying client does).
// `--serve` only publishes (advertised in the registry) so the topic commands can be tried by hand.
#include "bench/topic_hz.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <thread>

#include "common/shutdown.hpp"
#include "stats/percentile.hpp"
#include "stats/topic_meter.hpp"
#include "transport/registry.hpp"
#include "transport/typed.hpp"

namespace faultline::bench {
namespace {

struct RoundResult {
  std::uint64_t sent = 0, received = 0;
  double publisher_rate_hz = 0, measured_rate_hz = 0, bw_mb_s = 0, period_std_ms = 0,
         delay_p50_ms = 0, delay_p99_ms = 0;
};

// Sends frames on an absolute schedule until `count` are sent or `stop`; records send times.
void publish(const TopicHzOptions& o, transport::Publisher& pub, std::uint64_t count,
             const std::atomic<bool>& stop, std::vector<StampNs>* send_ns) {
  const std::size_t bytes = static_cast<std::size_t>(o.width) * o.height * 3;
  const auto pixels = std::make_shared<const std::vector<std::uint8_t>>(bytes, std::uint8_t{0x42});
  msgs::CameraFrame header;
  header.set_camera("CAM_BENCH");
  header.set_encoding("rgb8");
  header.set_width(o.width);
  header.set_height(o.height);
  header.set_step(o.width * 3);
  header.mutable_header()->set_publisher("bench_topic_hz");
  header.mutable_header()->set_frame_id("cam_bench");
  SystemClock clock;
  const StampNs t0 = clock.now_ns() + 20 * kNsPerMs;
  for (std::uint64_t i = 0; (count == 0 || i < count) && !stop.load(); ++i) {
    clock.sleep_until_ns(t0 + static_cast<StampNs>(static_cast<double>(i) * 1e9 / o.rate_hz));
    header.mutable_header()->set_seq(i + 1);
    header.mutable_header()->set_capture_stamp_ns(realtime_now_ns());
    header.mutable_header()->set_capture_clock(msgs::CAPTURE_CLOCK_REALTIME);
    header.mutable_header()->set_publish_stamp_ns(realtime_now_ns());
    const StampNs now = monotonic_now_ns();
    header.mutable_header()->set_publish_mono_ns(now);
    if (send_ns) send_ns->push_back(now);
    if (!transport::send_camera_frame(pub, o.topic, header, transport::Payload::of(pixels))) break;
  }
}

RoundResult run_round(const TopicHzOptions& o, const std::string& endpoint, bool copy_payload) {
  const auto frames = static_cast<std::uint64_t>(o.duration_s * o.rate_hz);
  // Bound here (so a tcp port can be OS-chosen), then handed to the publisher thread for good.
  transport::PublisherConfig pc;
  pc.endpoint = endpoint;
  pc.snd_hwm = o.hwm;
  transport::Publisher bound(pc);
  transport::SubscriberConfig sc;
  sc.endpoints = {bound.endpoint()};
  sc.topics = {o.topic};
  sc.rcv_hwm = o.hwm;
  transport::RawSubscriber sub(sc);
  std::atomic<bool> done{false};
  std::vector<StampNs> send_ns;
  std::thread publisher([&, pub = std::move(bound)]() mutable {
    if (!pub.wait_for_subscribers(o.topic, 1, 10 * kNsPerSec, &done)) return;
    publish(o, pub, frames, done, &send_ns);
    while (!done.load()) std::this_thread::yield();  // LINGER 0: stay open until the probe is done
  });
  std::vector<std::uint8_t> copy;
  const stats::ProbeReceive receive = [&](DurationNs timeout_ns) -> Result<stats::ProbeSample> {
    auto r = sub.receive(timeout_ns);
    if (!r.is_ok()) return r.status();
    if (copy_payload) copy.assign(r->payload_data(), r->payload_data() + r->payload_size());
    return stats::ProbeSample{r->receive_mono_ns(), r->size_bytes(), stats::kNoDelay};
  };
  stats::ProbeOptions po;
  po.max_messages = frames;
  po.duration_ns = static_cast<DurationNs>((o.duration_s + 3) * 1e9);  // frames lost: end anyway
  po.report_every_ns = 0;
  std::atomic<bool> stop{false};
  const auto result = stats::run_probe(receive, po, stop, nullptr);
  done.store(true);
  publisher.join();
  RoundResult rr;
  rr.sent = send_ns.size();
  rr.received = result.total.count;
  if (send_ns.size() >= 2) {
    rr.publisher_rate_hz = static_cast<double>(send_ns.size() - 1) /
                           (static_cast<double>(send_ns.back() - send_ns.front()) / 1e9);
  }
  rr.measured_rate_hz = result.total.rate_hz;
  rr.bw_mb_s = result.total.bytes_per_s / 1e6;
  rr.period_std_ms = result.total.period_ms.stddev;
  return rr;
}

int serve(const TopicHzOptions& o) {
  transport::PublisherConfig pc;
  pc.endpoint = o.endpoint.empty() ? "tcp://127.0.0.1:*" : o.endpoint;
  pc.snd_hwm = o.hwm;
  transport::Publisher pub(pc);
  transport::TopicRegistry registry("bench_topic_hz");
  (void)registry.advertise(o.topic, "faultline.msgs.CameraFrame", pub.endpoint());
  std::printf("publishing %s at %.1f Hz (%ux%u rgb8) on %s; Ctrl-C to stop\n", o.topic.c_str(),
              o.rate_hz, o.width, o.height, pub.endpoint().c_str());
  std::fflush(stdout);
  const auto frames = o.duration_s > 0 ? static_cast<std::uint64_t>(o.duration_s * o.rate_hz) : 0;
  publish(o, pub, frames, shutdown_requested(), nullptr);
  return 0;
}

}  // namespace

int run_topic_hz(const TopicHzOptions& o) {
  if (o.serve) return serve(o);
  const int repeat = o.repeat;
  const std::string& transport_kind = o.transport;
  std::printf(
      "bench topic-hz: %ux%u rgb8 (%.2f MB) at %.1f Hz for %.1f s over %s, %d rounds per mode\n",
      o.width, o.height, o.width * o.height * 3 / 1e6, o.rate_hz, o.duration_s,
      transport_kind.c_str(), repeat);
  std::printf("%-10s %8s %8s %12s %12s %10s %10s\n", "receiver", "sent", "recv", "pub_hz",
              "measured_hz", "MB/s", "std_ms");
  int failures = 0;
  for (const bool copy : {false, true}) {
    std::vector<double> measured, published, bw, std_ms;
    std::uint64_t sent = 0, received = 0;
    for (int i = 0; i < repeat; ++i) {
      const std::string ep = transport_kind == "ipc"
                                 ? "ipc:///tmp/faultline-bench-hz-" + std::to_string(::getpid())
                             : transport_kind == "tcp" ? std::string("tcp://127.0.0.1:*")
                                                       : "inproc://bench-hz-" + std::to_string(i);
      const RoundResult r = run_round(o, ep, copy);
      sent += r.sent;
      received += r.received;
      measured.push_back(r.measured_rate_hz);
      published.push_back(r.publisher_rate_hz);
      bw.push_back(r.bw_mb_s);
      std_ms.push_back(r.period_std_ms);
    }
    if (received != sent) ++failures;
    std::printf("%-10s %8llu %8llu %12.3f %12.3f %10.1f %10.3f\n", copy ? "copying" : "in-place",
                static_cast<unsigned long long>(sent), static_cast<unsigned long long>(received),
                stats::median(published), stats::median(measured), stats::median(bw),
                stats::median(std_ms));
  }
  std::printf("summary rounds=%d lost_rounds=%d (medians over rounds; counts summed)\n", repeat,
              failures);
  return failures == 0 ? 0 : 1;
}

}  // namespace faultline::bench
