// stale_frames through the parallel injector without sockets: a lagged camera's frames leave the
// pipeline as many frame periods late as configured, in capture order, with their original stamps;
// the frames still held at the stream end are flushed before it, and a stop counts them. Time is
// the stream's own: the clock reads the receive time of the newest frame sent, so the output order
// is a fact of the sequence, not of how fast the machine runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <string>
#include <utility>
#include <vector>

#include "common/logging.hpp"
#include "policy/fault_spec.hpp"
#include "runtime/engine_policy.hpp"
#include "runtime/injector_pipeline.hpp"

namespace faultline::runtime {
namespace {

constexpr StampNs kT0 = 1'600'000'000'000'000'000;  // capture stamp of instant 0
constexpr StampNs kMono0 = 1'000 * kNsPerSec;       // receive time of instant 0
constexpr DurationNs kPeriodNs = 100'000'000;       // 10 Hz
constexpr int kInstants = 12;

// The stream's clock: the receive time of the newest frame the sink accepted. Only the output
// thread sends, so every read there sees a value fixed by the output order so far.
class StreamClock final : public Clock {
 public:
  StampNs now_ns() const override { return now_.load(); }
  StampNs realtime_ns() const override { return kT0; }
  void sleep_until_ns(StampNs /*deadline*/) override {}
  void advance_to(StampNs t) { now_.store(std::max(now_.load(), t)); }

 private:
  std::atomic<StampNs> now_{kMono0 - 1};
};

struct Out {
  std::string topic;
  std::uint64_t source_seq = 0;
  StampNs capture_stamp_ns = 0;
  msgs::FaultState fault;
};

class StreamSink final : public PipelineSink {
 public:
  explicit StreamSink(StreamClock& clock) : clock_(clock) {}
  Status send_frame(const std::string& topic, msgs::CameraFrame& h,
                    const transport::Payload&) override {
    frames.push_back({topic, h.source_seq(), h.header().capture_stamp_ns(), h.fault()});
    clock_.advance_to(kMono0 + (h.header().capture_stamp_ns() - kT0));
    return Status::ok();
  }
  Status send_message(const std::string& topic, const google::protobuf::MessageLite&) override {
    messages.push_back(topic);
    if (topic == "/sync/end") frames_before_end = frames.size();
    return Status::ok();
  }
  std::vector<Out> frames;
  std::vector<std::string> messages;
  std::size_t frames_before_end = 0;

 private:
  StreamClock& clock_;
};

// CAM_FRONT lagged 300 ms (3 periods), CAM_BACK fresh; per instant front then back, as received.
class StaleFramesPipelineTest : public ::testing::Test {
 protected:
  StaleFramesPipelineTest()
      : policy_(make_frame_policy(
            YAML::Load("[{type: stale_frames, delay_ms: 300, cameras: CAM_FRONT}]"), "", 3,
            "test")),
        sink_(clock_),
        bytes_(std::make_shared<std::vector<std::uint8_t>>(64, 0x5A)) {
    PipelineConfig pc;
    pc.workers = 2;
    pc.queue_frames = 4;
    pipeline_ = std::make_unique<InjectorPipeline>(
        pc, *policy_, sink_, clock_, logging::make_node_logger("stale_pipeline_test", "warn"));
  }

  void SubmitAll() {
    for (int k = 0; k < kInstants; ++k) {
      for (const char* cam : {"CAM_FRONT", "CAM_BACK"}) {
        InputFrame f;
        f.topic = std::string("/") + cam;
        f.out_topic = "/faulty/" + std::string(cam);
        f.view.header.set_camera(cam);
        f.view.header.set_encoding("jpeg");
        f.view.header.set_source_seq(static_cast<std::uint64_t>(k + 1));
        f.view.header.mutable_header()->set_seq(static_cast<std::uint64_t>(k + 1));
        f.view.header.mutable_header()->set_capture_stamp_ns(kT0 + k * kPeriodNs);
        f.view.payload = bytes_->data();
        f.view.payload_size = bytes_->size();
        f.owner = bytes_;
        f.receive_mono_ns = kMono0 + k * kPeriodNs;
        ASSERT_TRUE(pipeline_->submit_frame(std::move(f), stop_));
      }
    }
  }

  std::unique_ptr<FramePolicy> policy_;
  StreamClock clock_;
  StreamSink sink_;
  std::shared_ptr<std::vector<std::uint8_t>> bytes_;
  std::atomic<bool> stop_{false};
  std::unique_ptr<InjectorPipeline> pipeline_;
};

TEST_F(StaleFramesPipelineTest, LaggedFramesLeaveThreePeriodsLateWithTheirStamps) {
  SubmitAll();
  msgs::StreamEnd end;
  end.set_frames_sent(2 * kInstants);
  ASSERT_TRUE(pipeline_->submit_control("/sync/end", end, true, stop_));
  pipeline_->finish(true);
  ASSERT_TRUE(pipeline_->failure().is_ok());

  // Front frame j is due 300 ms after its receive time: it leaves right after the back frame of
  // instant j + 3 (the first send at or past its due time); the last three wait for the stream end.
  std::vector<std::pair<std::string, std::uint64_t>> expected;
  for (std::uint64_t k = 1; k <= kInstants; ++k) {
    expected.emplace_back("/faulty/CAM_BACK", k);
    if (k >= 4) expected.emplace_back("/faulty/CAM_FRONT", k - 3);
  }
  for (std::uint64_t k = kInstants - 2; k <= kInstants; ++k)
    expected.emplace_back("/faulty/CAM_FRONT", k);
  std::vector<std::pair<std::string, std::uint64_t>> got;
  for (const Out& o : sink_.frames) got.emplace_back(o.topic, o.source_seq);
  EXPECT_EQ(got, expected);

  for (const Out& o : sink_.frames) {
    EXPECT_EQ(o.capture_stamp_ns, kT0 + static_cast<StampNs>(o.source_seq - 1) * kPeriodNs)
        << "stamps stay: " << o.topic << " seq " << o.source_seq;
    if (o.topic != "/faulty/CAM_FRONT") {
      EXPECT_EQ(o.fault.action(), msgs::FAULT_ACTION_PASS);
      continue;
    }
    EXPECT_EQ(o.fault.action(), msgs::FAULT_ACTION_DELAY);
    ASSERT_EQ(o.fault.faults_size(), 1);
    EXPECT_EQ(o.fault.faults(0).name(), "stale_frames");
    EXPECT_EQ(o.fault.faults(0).params().at("delay_ms"), 300.0);
  }
  // Every frame accounted for: sent, with one FaultEvent each, all before the stream end.
  const PipelineCounts c = pipeline_->counts();
  EXPECT_EQ(c.frames_out, 2u * kInstants);
  EXPECT_EQ(c.discarded_at_stop, 0u);
  EXPECT_EQ(sink_.frames_before_end, 2u * kInstants);
  EXPECT_EQ(std::count(sink_.messages.begin(), sink_.messages.end(), "/faultline/faults"),
            2 * kInstants);
  EXPECT_EQ(sink_.messages.back(), "/sync/end");
}

// Stopped without draining: the frames still held (never due: the stream did not reach their
// time) are not sent, and every frame is either sent or counted.
TEST_F(StaleFramesPipelineTest, StopCountsTheFramesStillHeld) {
  SubmitAll();
  pipeline_->finish(false);
  const PipelineCounts c = pipeline_->counts();
  EXPECT_EQ(c.frames_out + c.discarded_at_stop, 2u * kInstants);
  EXPECT_EQ(c.frames_out, sink_.frames.size());
  EXPECT_GE(c.discarded_at_stop, 3u);
  for (const Out& o : sink_.frames) {
    EXPECT_FALSE(o.topic == "/faulty/CAM_FRONT" && o.source_seq > kInstants - 3)
        << "front frame " << o.source_seq << " was not due";
  }
}

}  // namespace
}  // namespace faultline::runtime
