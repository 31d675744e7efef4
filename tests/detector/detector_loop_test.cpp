// The detector node's loop: a sample boundary lost in transport (#22 item 6) is counted, never
// skipped silently; DetectionArrays carry the loop clock's stamps and processing time.
#include "detector/detector_loop.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <future>

#include "common/logging.hpp"
#include "detection.pb.h"
#include "manual_clock.hpp"  // tests/
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
  constexpr StampNs kStart = 300 * kNsPerSec, kOffset = 1'700'000'000 * kNsPerSec;
  ManualClock clock(kStart, kOffset);  // frozen: no processing time, every stamp kStart
  DetectorLoop loop(cfg, "detector", logging::make_node_logger("detector_loop_test", "error"),
                    clock);
  std::atomic<bool> stop{false};
  auto rc = std::async(std::launch::async, [&] { return loop.run(stop); });
  ASSERT_TRUE(injector.wait_for_subscribers("/sync/sample", 1, 20 * kNsPerSec).is_ok());
  // Boundaries 3 and 4 never arrive (as when a full queue dropped them with the frames around
  // them).
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
    EXPECT_EQ(d.header().publish_mono_ns(), kStart);
    EXPECT_EQ(d.header().publish_stamp_ns(), kStart + kOffset);
    EXPECT_EQ(d.processing_ns(), 0);
  }
  EXPECT_EQ(rc.get(), 0);
  EXPECT_EQ(tokens, (std::vector<std::string>{"sample-1", "sample-2", "sample-5"}));
  EXPECT_EQ(loop.counts().boundaries, 3u);
  EXPECT_EQ(loop.counts().boundaries_lost, 2u);
  EXPECT_EQ(loop.counts().stream_breaks,
            1u);  // sample-5 follows the gap: named, motion history reset
}

// A detector that joins mid-sample (a respawn) or loses key frames counts them from the boundary's
// frames_sent.
TEST(DetectorLoopTest, KeyFramesMissingFromASampleAreCountedFromItsBoundary) {
  const std::string dir = ::testing::TempDir() + "detector_keys_" + std::to_string(::getpid());
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
  cfg.temporal = false;
  DetectorLoop loop(cfg, "detector", logging::make_node_logger("detector_keys_test", "error"));
  std::atomic<bool> stop{false};
  auto rc = std::async(std::launch::async, [&] { return loop.run(stop); });
  ASSERT_TRUE(injector.wait_for_subscribers("/sync/sample", 1, 20 * kNsPerSec).is_ok());
  std::uint64_t seq = 0;
  auto frame = [&](const std::string& camera, const std::string& token) {
    msgs::CameraFrame h;
    h.set_camera(camera);
    h.set_sample_token(token);
    h.set_is_key_frame(true);
    h.set_encoding("jpeg");
    h.mutable_header()->set_seq(++seq);
    h.mutable_header()->set_publisher("fault_injector");
    auto bytes = std::make_shared<const std::vector<std::uint8_t>>(
        std::vector<std::uint8_t>{0xFF, 0xD8, 0xFF, 0xD9});
    ASSERT_TRUE(transport::send_camera_frame(injector, "/faulty/" + camera, h,
                                             transport::Payload::of(bytes))
                    .is_ok());
  };
  auto boundary = [&](const std::string& token, std::uint32_t frames_sent, bool last) {
    msgs::SampleBoundary b;
    b.mutable_header()->set_seq(++seq);
    b.mutable_header()->set_publisher("fault_injector");
    b.set_sample_token(token);
    b.set_frames_sent(frames_sent);
    b.set_last_in_run(last);
    ASSERT_TRUE(transport::send_message(injector, "/sync/sample", b).is_ok());
  };
  frame("CAM_FRONT", "s1");
  frame("CAM_BACK", "s1");
  boundary("s1", 2, false);  // complete
  frame("CAM_FRONT", "s2");
  boundary("s2", 3, true);  // two of its three key frames never came
  int arrays = 0;
  const StampNs deadline = monotonic_now_ns() + 30 * kNsPerSec;  // watchdog, not synchronisation
  while (arrays < 2 && monotonic_now_ns() < deadline)
    arrays += sink.receive(50 * kNsPerMs).is_ok() ? 1 : 0;
  EXPECT_EQ(rc.get(), 0);
  EXPECT_EQ(arrays, 2);
  EXPECT_EQ(loop.counts().incomplete_samples, 1u);
  EXPECT_EQ(loop.counts().key_frames_missing, 2u);
}

// Frames from an injector with output_shm are read from its ring; one whose slot was reused before
// the detector read it is counted (shm_overwritten), neither malformed nor silently skipped.
TEST(DetectorLoopTest, SharedMemoryFramesAreReadAndOverwrittenOnesCounted) {
  const std::string dir = ::testing::TempDir() + "detector_shm_" + std::to_string(::getpid());
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
  cfg.temporal = false;
  DetectorLoop loop(cfg, "detector", logging::make_node_logger("detector_shm_test", "error"));
  std::atomic<bool> stop{false};
  auto rc = std::async(std::launch::async, [&] { return loop.run(stop); });
  ASSERT_TRUE(injector.wait_for_subscribers("/sync/sample", 1, 20 * kNsPerSec).is_ok());
  transport::ShmRingConfig ring_cfg;
  ring_cfg.path = dir + ".ring";
  ring_cfg.slot_count = 2;
  ring_cfg.slot_bytes = 16;
  transport::ShmRingWriter ring(ring_cfg);
  const std::vector<std::uint8_t> jpeg{0xFF, 0xD8, 0xFF, 0xD9};
  auto header = [&](const std::string& camera, std::uint64_t seq) {
    msgs::CameraFrame h;
    h.set_camera(camera);
    h.set_sample_token("s1");
    h.set_is_key_frame(true);
    h.set_encoding("jpeg");
    h.mutable_header()->set_seq(seq);
    h.mutable_header()->set_publisher("fault_injector");
    return h;
  };
  // A descriptor sent only after its slot was reused: stale on arrival, whatever the timing.
  auto stale = ring.write(jpeg.data(), jpeg.size());
  ASSERT_TRUE(stale.is_ok());
  ASSERT_TRUE(ring.write(jpeg.data(), jpeg.size()).is_ok());
  ASSERT_TRUE(ring.write(jpeg.data(), jpeg.size()).is_ok());
  msgs::CameraFrame h = header("CAM_FRONT", 1);
  h.set_payload_bytes(static_cast<std::uint32_t>(jpeg.size()));
  h.mutable_shm()->set_path(ring.path());
  h.mutable_shm()->set_ring_id(stale->ring_id);
  h.mutable_shm()->set_slot(stale->slot);
  h.mutable_shm()->set_sequence(stale->sequence);
  h.mutable_shm()->set_offset(stale->offset);
  ASSERT_TRUE(injector.send("/faulty/CAM_FRONT", h.SerializeAsString()).is_ok());
  msgs::CameraFrame good = header("CAM_BACK", 1);
  ASSERT_TRUE(transport::send_camera_frame_shm(
                  injector, ring, "/faulty/CAM_BACK", good,
                  transport::Payload::of(std::make_shared<const std::vector<std::uint8_t>>(jpeg)))
                  .is_ok());
  msgs::SampleBoundary b;
  b.mutable_header()->set_seq(1);
  b.mutable_header()->set_publisher("fault_injector");
  b.set_sample_token("s1");
  b.set_frames_sent(2);
  b.set_last_in_run(true);
  ASSERT_TRUE(transport::send_message(injector, "/sync/sample", b).is_ok());
  int arrays = 0;
  const StampNs deadline = monotonic_now_ns() + 30 * kNsPerSec;  // watchdog, not synchronisation
  while (arrays < 1 && monotonic_now_ns() < deadline)
    arrays += sink.receive(50 * kNsPerMs).is_ok() ? 1 : 0;
  EXPECT_EQ(rc.get(), 0);
  EXPECT_EQ(arrays, 1);
  EXPECT_EQ(loop.counts().frames, 1u);
  EXPECT_EQ(loop.counts().shm_overwritten, 1u);
  EXPECT_EQ(loop.counts().malformed, 0u);
}

}  // namespace
}  // namespace faultline::detector
