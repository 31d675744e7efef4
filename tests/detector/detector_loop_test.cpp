// The detector node's loop: a sample boundary lost in transport (#22 item 6) is counted, never skipped silently.
#include <gtest/gtest.h>
#include <unistd.h>

#include <future>

#include "common/logging.hpp"
#include "detection.pb.h"
#include "detector/detector_loop.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::detector {
namespace {

TEST(DetectorLoopTest, BoundariesLostInTransportAreCountedFromTheSeqGap) {
  const std::string dir = ::testing::TempDir() + "detector_loop_" + std::to_string(::getpid());
  transport::PublisherConfig pc;
  pc.endpoint = "ipc://" + dir + "_injector.sock";
  pc.snd_hwm = 100;
  transport::Publisher injector(pc);
  transport::SubscriberConfig kc;
  kc.endpoints = {"ipc://" + dir + "_sink.sock"};
  kc.pattern = transport::Pattern::PushPull;
  kc.bind = true;
  kc.rcv_hwm = 100;
  transport::RawSubscriber sink(kc);

  DetectorLoopConfig cfg;
  cfg.input_endpoints = {injector.endpoint()};
  cfg.sink_endpoint = sink.endpoints().front();
  DetectorLoop loop(cfg, "detector", logging::make_node_logger("detector_loop_test", "error"));
  std::atomic<bool> stop{false};
  auto rc = std::async(std::launch::async, [&] { return loop.run(stop); });
  ASSERT_TRUE(injector.wait_for_subscribers("/sync/sample", 1, 20 * kNsPerSec).is_ok());
  // Boundaries 3 and 4 never arrive (as when a full queue dropped them with the frames around them).
  for (std::uint64_t seq : {1, 2, 5}) {
    msgs::SampleBoundary b;
    b.mutable_header()->set_seq(seq);
    b.mutable_header()->set_publisher("fault_injector");
    b.set_sample_token("sample-" + std::to_string(seq));
    b.set_timestamp_us(static_cast<std::int64_t>(seq) * 500'000);
    b.set_last_in_run(seq == 5);
    ASSERT_TRUE(transport::send_message(injector, "/sync/sample", b).is_ok());
  }
  std::vector<std::string> tokens;
  const StampNs deadline = monotonic_now_ns() + 30 * kNsPerSec;  // watchdog, not synchronisation
  while (tokens.size() < 3 && monotonic_now_ns() < deadline) {
    auto r = sink.receive(50 * kNsPerMs);
    if (!r.is_ok()) continue;
    msgs::DetectionArray d;
    ASSERT_TRUE(transport::parse_message(*r, &d).is_ok());
    tokens.push_back(d.sample_token());
  }
  EXPECT_EQ(rc.get(), 0);
  EXPECT_EQ(tokens, (std::vector<std::string>{"sample-1", "sample-2", "sample-5"}));
  EXPECT_EQ(loop.counts().boundaries, 3u);
  EXPECT_EQ(loop.counts().boundaries_lost, 2u);
}

}  // namespace
}  // namespace faultline::detector
