// `topic hz` counting end to end: a publisher thread sends 4.32 MB raw frames at 72 Hz over ipc on
// an absolute schedule; the probe loop with a real RawSubscriber must count every frame and measure
// the publisher's rate. This checks counting, not speed, so it holds on a loaded machine: the
// publisher never runs more than a few frames ahead of what the probe has counted (a busy machine
// slows the stream instead of making the queues drop), and the rate is compared with the rate
// computed from the publisher's own send stamps, never with the wall clock.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "stats/topic_meter.hpp"
#include "transport/typed.hpp"

namespace faultline::stats {
namespace {

constexpr int kFrames = 144;  // 2 s at 72 Hz
constexpr std::size_t kFrameBytes = 1600 * 900 * 3;
constexpr int kMaxAhead =
    4;  // frames the publisher may run ahead of the probe: well below both HWMs (8)
const std::string kTopic = "/cam_front/image_raw";

TEST(TopicHzEndToEndTest, CountsEveryFourMegabyteFrameAtSeventyTwoHertz) {
  const std::string endpoint = "ipc:///tmp/faultline-topic-hz-e2e-" + std::to_string(::getpid());
  transport::SubscriberConfig sc;
  sc.endpoints = {endpoint};
  sc.topics = {kTopic};
  sc.rcv_hwm = 8;
  transport::RawSubscriber subscriber(sc);

  std::vector<StampNs> send_ns;
  std::string publisher_error;
  std::atomic<bool> stop{false};
  std::atomic<int> counted{0};  // frames the probe has received
  std::thread publisher([&] {
    transport::PublisherConfig pc;
    pc.endpoint = endpoint;
    pc.snd_hwm = 8;
    transport::Publisher pub(pc);
    if (const Status s = pub.wait_for_subscribers(kTopic, 1, 10 * kNsPerSec, &stop); !s) {
      publisher_error = s.to_string();
      return;
    }
    const auto pixels =
        std::make_shared<const std::vector<std::uint8_t>>(kFrameBytes, std::uint8_t{0x5a});
    msgs::CameraFrame header;
    header.set_camera("CAM_FRONT");
    header.set_encoding("rgb8");
    header.set_width(1600);
    header.set_height(900);
    header.set_step(1600 * 3);
    SystemClock clock;
    const StampNs t0 = clock.now_ns() + 20 * kNsPerMs;
    for (int i = 0; i < kFrames && !stop.load(); ++i) {
      clock.sleep_until_ns(t0 + static_cast<StampNs>(i) * kNsPerSec /
                                    72);  // absolute schedule: no drift
      while (i - counted.load() >= kMaxAhead && !stop.load()) {
        std::this_thread::sleep_for(std::chrono::microseconds(250));
      }
      header.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
      header.mutable_header()->set_capture_stamp_ns(realtime_now_ns());
      send_ns.push_back(monotonic_now_ns());
      header.mutable_header()->set_publish_mono_ns(send_ns.back());
      if (const Status s =
              transport::send_camera_frame(pub, kTopic, header, transport::Payload::of(pixels));
          !s) {
        publisher_error = s.to_string();
        return;
      }
    }
    // LINGER is 0: closing now could discard the last frames, so stay open until the probe is done.
    const StampNs deadline = monotonic_now_ns() + 120 * kNsPerSec;
    while (!stop.load() && monotonic_now_ns() < deadline) std::this_thread::yield();
  });

  TopicMeter stamp_meter;
  const ProbeReceive receive = [&](DurationNs timeout_ns) -> Result<ProbeSample> {
    auto r = subscriber.receive(timeout_ns);
    if (!r.is_ok()) return r.status();
    counted.fetch_add(1);
    // Test-only bookkeeping: the publisher's send stamps as they arrived, to compare counts
    // exactly.
    const auto frame = transport::parse_camera_frame(*r);
    if (frame.is_ok()) stamp_meter.add(frame->header.header().publish_mono_ns(), r->size_bytes());
    return ProbeSample{r->receive_mono_ns(), r->size_bytes(), kNoDelay};
  };
  ProbeOptions options;
  options.max_messages = kFrames;
  options.duration_ns = 120 * kNsPerSec;  // bound if frames go missing
  options.report_every_ns = 0;
  const ProbeResult result = run_probe(receive, options, stop, nullptr);
  stop.store(true);
  publisher.join();

  ASSERT_EQ(publisher_error, "");
  ASSERT_EQ(send_ns.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(result.end, ProbeEnd::MessageCount);
  EXPECT_EQ(result.total.count, static_cast<std::uint64_t>(kFrames));
  EXPECT_GE(result.total.size_bytes.min, static_cast<double>(kFrameBytes));
  const double publisher_rate_hz =
      (kFrames - 1) / (static_cast<double>(send_ns.back() - send_ns.front()) / 1e9);
  // Exact: every frame arrived with its send stamp, so the rate over send stamps is the
  // publisher's.
  EXPECT_EQ(stamp_meter.total().count, static_cast<std::uint64_t>(kFrames));
  EXPECT_NEAR(stamp_meter.total().rate_hz, publisher_rate_hz, 1e-9 * publisher_rate_hz);
  // The probe's own figure, from receive times, depends on the machine's load: printed, not
  // asserted.
  std::printf("measured %.3f Hz, publisher %.3f Hz, %.1f MB/s, period std %.3f ms\n",
              result.total.rate_hz, publisher_rate_hz, result.total.bytes_per_s / 1e6,
              result.total.period_ms.stddev);
}

}  // namespace
}  // namespace faultline::stats
