// The parallel injector without sockets: the same frames through 1, 2 and 4 workers give
// byte-identical output (headers, seqs, payloads, FaultEvents, control messages, order), with
// coherent faults, a schedule, freeze, frame_lost, delay and crash, Faultline's stream faults (a
// coherent transport corruption, recompression, timestamp skew, calibration drift, rolling shutter
// from the ego poses); a stateful lane renders in plan order; the delay queue's order.
#include "runtime/injector_pipeline.hpp"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "codec/jpeg.hpp"
#include "common/config.hpp"
#include "common/logging.hpp"
#include "policy/temporal_draws.hpp"
#include "runtime/delay_queue.hpp"
#include "runtime/engine_policy.hpp"
#include "runtime/injector_loop.hpp"

namespace faultline::runtime {
namespace {

constexpr StampNs kT0 = 1'600'000'000'000'000'000;

// Time stands still, so stamps and latencies are the same in every run.
class FixedClock final : public Clock {
 public:
  StampNs now_ns() const override { return 50 * kNsPerSec; }
  StampNs realtime_ns() const override { return kT0 + 99 * kNsPerSec; }
  void sleep_until_ns(StampNs /*deadline*/) override {}
};

struct Sent {
  std::string topic;
  std::string header;   // serialised header / message
  std::string payload;  // frame bytes
  bool operator==(const Sent& o) const {
    return topic == o.topic && header == o.header && payload == o.payload;
  }
};

// Protobuf map fields (fault params) serialise in hash order unless asked for a deterministic
// order.
std::string Serialize(const google::protobuf::MessageLite& m) {
  std::string out;
  {
    google::protobuf::io::StringOutputStream stream(&out);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    m.SerializeToCodedStream(&coded);
  }
  return out;
}

class RecordingSink final : public PipelineSink {
 public:
  Status send_frame(const std::string& topic, msgs::CameraFrame& h,
                    const transport::Payload& p) override {
    h.set_payload_bytes(p.size_bytes);
    sent.push_back(
        {topic, Serialize(h), std::string(reinterpret_cast<const char*>(p.data), p.size_bytes)});
    return Status::ok();
  }
  Status send_message(const std::string& topic, const google::protobuf::MessageLite& m) override {
    sent.push_back({topic, Serialize(m), ""});
    return Status::ok();
  }
  std::vector<Sent> sent;
};

// One camera frame with its own bytes: a textured image that changes per instant and camera.
struct Input {
  std::string topic;
  std::shared_ptr<std::vector<std::uint8_t>> bytes;
  msgs::CameraFrame header;
};

std::vector<Input> MakeInputs(int instants) {
  std::vector<Input> inputs;
  for (int k = 0; k < instants; ++k) {
    for (int cam = 0; cam < policy::kNumCameras; ++cam) {
      cv::Mat img(90, 160, CV_8UC3);
      cv::randu(img, cv::Scalar::all(0), cv::Scalar::all(255));
      cv::rectangle(img, {10 + 7 * k, 10}, {60 + 7 * k, 50 + 5 * cam},
                    cv::Scalar(40 * cam, 200, 30 * k), cv::FILLED);
      Input in;
      in.bytes = std::make_shared<std::vector<std::uint8_t>>(*codec::encode_jpeg(img, 90));
      in.topic = std::string("/cam_") + std::to_string(cam) + "/image_rect_compressed";
      in.header.set_camera(policy::kCameraNames[cam]);
      in.header.set_encoding("jpeg");
      in.header.set_source_seq(static_cast<std::uint64_t>(k + 1));
      in.header.set_is_key_frame(k % 2 == 0);
      in.header.mutable_header()->set_seq(static_cast<std::uint64_t>(k + 1));
      in.header.mutable_header()->set_publisher("source");
      in.header.mutable_header()->set_capture_stamp_ns(kT0 + k * kNsPerSec / 12);
      in.header.set_payload_bytes(in.bytes->size());
      // The ego turns left at 0.6 rad/s (0.05 rad per 1/12 s): rolling_shutter's yaw rate, and the
      // glare follows it; every camera looks along the ego's x axis.
      auto* ego = in.header.mutable_ego_pose()->mutable_rotation();
      ego->set_w(std::cos(0.025 * k));
      ego->set_z(std::sin(0.025 * k));
      auto* cam_rot = in.header.mutable_sensor_to_ego()->mutable_rotation();
      cam_rot->set_w(0.5), cam_rot->set_x(-0.5), cam_rot->set_y(0.5), cam_rot->set_z(-0.5);
      in.header.mutable_sensor_to_ego()->mutable_translation()->set_x(1.7);
      for (double v : {120.0, 0.0, 80.0, 0.0, 120.0, 45.0, 0.0, 0.0, 1.0})
        in.header.add_intrinsics(v);
      inputs.push_back(std::move(in));
    }
  }
  return inputs;
}

// Coherent faults (fog ramping up, so its per-camera state restarts at each step), a ramp and a
// window (schedule), per-frame seeds in numpy mode, freeze history, frame_lost, delay and a crash,
// the sensor faults (coherent by default; glare following the ego pose), the stream and message
// faults: every kind of state the engine carries between frames.
constexpr const char* kFaults = R"([
  {type: fog, severity: 3, coherent: true, cameras: [CAM_FRONT, CAM_FRONT_LEFT], ramp_s: 0.4},
  {type: motion_blur, severity: 4, coherent: true, cameras: CAM_BACK, ramp_s: 0.6},
  {type: snow, severity: 2, coherent: true, cameras: CAM_FRONT_RIGHT, start_s: 0.1, duration_s: 0.5},
  {type: dark, level: mid, rng: numpy, cameras: CAM_FRONT_RIGHT},
  {type: brightness, severity: 2, cameras: [CAM_BACK_LEFT]},
  {type: freeze, cameras: CAM_BACK_LEFT, start_s: 0.2, duration_s: 0.2},
  {type: frame_lost, severity: 2, rng: numpy, mode: drop},
  {type: delay, cameras: CAM_BACK_RIGHT, delay_ms: 100, start_s: 0.25},
  {type: camera_crash, severity: 1, mode: black, start_s: 0.7},
  {type: transport_corruption, severity: 3, coherent: true, cameras: CAM_BACK_RIGHT, start_s: 0.5},
  {type: recompression, severity: 2, cameras: CAM_FRONT},
  {type: timestamp_skew, severity: 3, cameras: CAM_FRONT_RIGHT},
  {type: calibration_drift, severity: 4, cameras: CAM_BACK_LEFT},
  {type: rolling_shutter, severity: 5, cameras: CAM_FRONT_LEFT},
  {type: soiling, severity: 4, cameras: CAM_FRONT},
  {type: glare, severity: 5, cameras: CAM_BACK_RIGHT, start_s: 0.1},
  {type: water_drops, severity: 5, cameras: CAM_BACK_LEFT},
  {type: exposure_flicker, severity: 5, cameras: CAM_FRONT_LEFT, start_s: 0.2}
])";

std::vector<Sent> RunPipeline(const std::vector<Input>& inputs, int workers, bool decode,
                              int queue_frames) {
  auto policy = make_frame_policy(YAML::Load(kFaults), "", 11, "test", 90);
  RecordingSink sink;
  FixedClock clock;
  PipelineConfig pc;
  pc.workers = workers;
  pc.decode = decode;
  pc.queue_frames = queue_frames;
  std::atomic<bool> stop{false};
  InjectorPipeline pipeline(pc, *policy, sink, clock,
                            logging::make_node_logger("pipeline_test", "warn"));
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const Input& in = inputs[i];
    InputFrame f;
    f.topic = in.topic;
    f.out_topic = "/faulty" + in.topic;
    f.view.header = in.header;
    f.view.payload = in.bytes->data();
    f.view.payload_size = in.bytes->size();
    f.owner = in.bytes;
    f.receive_mono_ns = 50 * kNsPerSec - 3 * kNsPerMs;
    EXPECT_TRUE(pipeline.submit_frame(std::move(f), stop));
    if ((i + 1) % policy::kNumCameras == 0) {
      msgs::SampleBoundary b;
      b.set_sample_token("s" + std::to_string(i / policy::kNumCameras));
      EXPECT_TRUE(pipeline.submit_control("/sync/sample", b, false, stop));
    }
  }
  msgs::StreamEnd e;
  e.set_frames_sent(inputs.size());
  EXPECT_TRUE(pipeline.submit_control("/sync/end", e, true, stop));
  pipeline.finish(true);
  EXPECT_TRUE(pipeline.failure().is_ok());
  EXPECT_EQ(pipeline.counts().discarded_at_stop, 0u);
  EXPECT_EQ(pipeline.workers(), workers);
  return sink.sent;
}

class InjectorPipelineTest : public ::testing::TestWithParam<bool> {};

TEST_P(InjectorPipelineTest, OutputIsByteIdenticalForAnyWorkerCount) {
  const bool decode = GetParam();
  const std::vector<Input> inputs = MakeInputs(12);
  const std::vector<Sent> one = RunPipeline(inputs, 1, decode, 4);

  // The reference run exercised every kind of fault: read the actions from its FaultEvents.
  std::map<int, int> actions;
  std::map<std::string, int> fault_names;
  std::size_t frames = 0, events = 0;
  std::map<std::string, std::uint64_t> last_seq;
  for (const Sent& s : one) {
    if (s.topic == "/faultline/faults") {
      msgs::FaultEvent e;
      ASSERT_TRUE(e.ParseFromString(s.header));
      ++actions[e.state().action()];
      for (const auto& f : e.state().faults()) ++fault_names[f.name()];
      ++events;
      EXPECT_EQ(e.header().seq(), events);
    } else if (s.topic.rfind("/faulty/", 0) == 0) {
      msgs::CameraFrame h;
      ASSERT_TRUE(h.ParseFromString(s.header));
      ++frames;
      EXPECT_EQ(h.header().seq(), ++last_seq[s.topic])
          << s.topic;  // the injector's own seq, gap-free
      EXPECT_EQ(h.encoding(), decode ? "bgr8" : "jpeg");
      // Message faults: CAM_FRONT_RIGHT's stamps 20 ms late, CAM_BACK_LEFT's calibration off, the
      // rest as sent.
      const StampNs sent_stamp = kT0 + static_cast<StampNs>(h.source_seq() - 1) * kNsPerSec / 12;
      EXPECT_EQ(h.header().capture_stamp_ns(),
                sent_stamp + (h.camera() == "CAM_FRONT_RIGHT" ? 20 * kNsPerMs : 0));
      const bool drifted = h.camera() == "CAM_BACK_LEFT";
      EXPECT_EQ(h.intrinsics(0) != 120.0, drifted) << h.camera();
      EXPECT_EQ(h.intrinsics(2), 80.0);
      EXPECT_EQ(h.sensor_to_ego().rotation().w() != 0.5, drifted) << h.camera();
      EXPECT_EQ(h.sensor_to_ego().translation().x() != 1.7, drifted) << h.camera();
      if (h.camera() == "CAM_FRONT_LEFT" && h.source_seq() > 1) {
        bool skewed = false;
        for (const auto& f : h.fault().faults()) {
          if (f.name() == "rolling_shutter")
            skewed = std::abs(f.params().at("yaw_rate_deg_s") - 0.6 * 180 / M_PI) < 1e-6;
        }
        EXPECT_TRUE(skewed) << "seq " << h.source_seq();
      }
    }
  }
  EXPECT_EQ(events, inputs.size());  // one FaultEvent per source frame
  EXPECT_EQ(frames + static_cast<std::size_t>(actions[msgs::FAULT_ACTION_DROP]), inputs.size());
  for (auto a : {msgs::FAULT_ACTION_PASS, msgs::FAULT_ACTION_CORRUPT, msgs::FAULT_ACTION_DROP,
                 msgs::FAULT_ACTION_BLACK, msgs::FAULT_ACTION_FREEZE, msgs::FAULT_ACTION_DELAY}) {
    EXPECT_GT(actions[a], 0) << "action " << a;
  }
  for (const char* name : {"soiling", "water_drops", "glare", "exposure_flicker"}) {
    EXPECT_GT(fault_names[name], 0) << name;
  }
  // Delayed frames (the clock stands still) leave just before the stream end, which stays last.
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(one.back().topic, "/sync/end");

  for (int workers : {2, 4}) {
    for (int queue : {4, 16}) {
      const std::vector<Sent> many = RunPipeline(inputs, workers, decode, queue);
      ASSERT_EQ(many.size(), one.size()) << workers << " workers, queue " << queue;
      for (std::size_t i = 0; i < one.size(); ++i) {
        ASSERT_EQ(many[i].topic, one[i].topic) << "message " << i << ", " << workers << " workers";
        ASSERT_EQ(many[i].header, one[i].header)
            << "message " << i << " on " << one[i].topic << ", " << workers << " workers";
        ASSERT_TRUE(many[i].payload == one[i].payload)
            << "payload " << i << " on " << one[i].topic << ", " << workers << " workers";
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Modes, InjectorPipelineTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& p) {
                           return p.param ? "Decode" : "Jpeg";
                         });

// A policy whose every frame is stateful in the lane of its camera: render() records the order it
// saw and burns a frame-dependent amount of CPU, so that with several workers later frames would
// overtake earlier ones.
class LaneRecordingPolicy final : public FramePolicy {
 public:
  PlannedFrame plan(const transport::CameraFrameView& frame) override {
    PlannedFrame p;
    p.lane = static_cast<int>(frame.header.source_seq() % 3);
    return p;
  }
  FaultDecision render(PlannedFrame& planned, const transport::CameraFrameView& frame,
                       cv::Mat*) override {
    volatile std::uint64_t x = 0;
    const std::uint64_t spins = (frame.header.header().seq() * 7919) % 200000;
    for (std::uint64_t i = 0; i < spins; ++i) x = x + i;
    order[static_cast<std::size_t>(planned.lane)].push_back(
        frame.header.header().seq());  // no lock: one at a time
    return {};
  }
  std::array<std::vector<std::uint64_t>, 3> order;
};

TEST(InjectorPipelineLaneTest, FramesOfOneLaneRenderInPlanOrder) {
  LaneRecordingPolicy policy;
  RecordingSink sink;
  FixedClock clock;
  PipelineConfig pc;
  pc.workers = 4;
  pc.queue_frames = 32;
  std::atomic<bool> stop{false};
  auto bytes = std::make_shared<std::vector<std::uint8_t>>(16, 7);
  {
    InjectorPipeline pipeline(pc, policy, sink, clock,
                              logging::make_node_logger("pipeline_test", "warn"));
    for (std::uint64_t seq = 1; seq <= 300; ++seq) {
      InputFrame f;
      f.topic = "/cam/image";
      f.out_topic = "/faulty/cam/image";
      f.view.header.set_source_seq(seq);
      f.view.header.mutable_header()->set_seq(seq);
      f.view.payload = bytes->data();
      f.view.payload_size = bytes->size();
      f.owner = bytes;
      ASSERT_TRUE(pipeline.submit_frame(std::move(f), stop));
    }
    pipeline.finish(true);
    EXPECT_EQ(pipeline.counts().frames_out, 300u);
  }
  for (std::size_t lane = 0; lane < 3; ++lane) {
    ASSERT_EQ(policy.order[lane].size(), 100u);
    for (std::size_t i = 0; i < 100; ++i)
      EXPECT_EQ(policy.order[lane][i], (lane == 0 ? 3 : lane) + 3 * i);
  }
  // Output order is input order.
  std::uint64_t expected = 0;
  for (const Sent& s : sink.sent) {
    if (s.topic != "/faulty/cam/image") continue;
    msgs::CameraFrame h;
    ASSERT_TRUE(h.ParseFromString(s.header));
    EXPECT_EQ(h.source_seq(), ++expected);
  }
  EXPECT_EQ(expected, 300u);
}

TEST(InjectorPipelineStopTest, FinishWithoutDrainCountsWhatWasNotSent) {
  LaneRecordingPolicy policy;
  RecordingSink sink;
  FixedClock clock;
  PipelineConfig pc;
  pc.workers = 2;
  pc.queue_frames = 8;
  std::atomic<bool> stop{false};
  auto bytes = std::make_shared<std::vector<std::uint8_t>>(16, 7);
  InjectorPipeline pipeline(pc, policy, sink, clock,
                            logging::make_node_logger("pipeline_test", "warn"));
  for (std::uint64_t seq = 1; seq <= 8; ++seq) {
    InputFrame f;
    f.view.header.set_source_seq(seq);
    f.view.payload = bytes->data();
    f.view.payload_size = bytes->size();
    f.owner = bytes;
    ASSERT_TRUE(pipeline.submit_frame(std::move(f), stop));
  }
  pipeline.finish(false);
  const PipelineCounts c = pipeline.counts();
  EXPECT_EQ(c.frames_out + c.discarded_at_stop, 8u);  // every frame is sent or counted
  stop = true;
  InputFrame late;
  late.owner = bytes;
  EXPECT_FALSE(pipeline.submit_frame(std::move(late), stop));
  EXPECT_EQ(pipeline.counts().discarded_at_stop, c.discarded_at_stop + 1);
}

TEST(InjectorConfigTest, WorkerCountsAreCheckedAndDefaultToTheCoresLessOne) {
  EXPECT_GE(default_worker_count(), 1);
  InjectorConfig c;
  c.workers = -1;
  try {
    c.validate();
    FAIL() << "workers = -1 accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("workers = -1"), std::string::npos) << e.what();
  }
  c.workers = 0;
  c.queue_frames = -2;
  EXPECT_THROW(c.validate(), ConfigError);
  c.queue_frames = 0;
  EXPECT_NO_THROW(c.validate());
}

TEST(DelayQueueTest, ReleasesInDueOrderAndKeepsPushOrderForTies) {
  DelayQueue<int> q;
  q.push(300, 1);
  q.push(100, 2);
  q.push(300, 3);
  q.push(200, 4);
  EXPECT_EQ(q.next_due_ns(), 100);
  EXPECT_FALSE(q.pop_due(99));
  EXPECT_EQ(q.pop_due(250), 2);
  EXPECT_EQ(q.pop_due(250), 4);
  EXPECT_FALSE(q.pop_due(250));
  EXPECT_EQ(q.pop_due(300), 1);
  EXPECT_EQ(q.pop_due(300), 3);
  EXPECT_TRUE(q.empty());
  EXPECT_FALSE(q.next_due_ns());
}

}  // namespace
}  // namespace faultline::runtime
