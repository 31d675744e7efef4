// The engine as the injector's FramePolicy: FaultDecision contents, JPEG passthrough (re-encode,
// black, freeze), decoded mode, config entry point, and a run through the real player and injector
// loops over ipc.
#include "runtime/engine_policy.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <future>
#include <opencv2/imgproc.hpp>

#include "codec/jpeg.hpp"
#include "common/config.hpp"
#include "common/logging.hpp"
#include "policy/seeding.hpp"
#include "runtime/injector_loop.hpp"
#include "runtime/player_loop.hpp"
#include "transport/drop_counter.hpp"
#include "transport/subscriber.hpp"

namespace faultline::runtime {
namespace {

using policy::EngineConfig;
using policy::frame_seed;
using policy::kCameraNames;
using policy::kNumCameras;
using policy::parse_faults;

constexpr StampNs kT0 = 1'600'000'000'000'000'000;

std::vector<std::uint8_t> Jpeg(int value, int w = 48, int h = 32) {
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(value, 255 - value, 90));
  cv::rectangle(img, {4, 4}, {w / 2, h / 2}, cv::Scalar(20, 200, value), cv::FILLED);
  return *codec::encode_jpeg(img, 95);
}

struct TestFrame {
  std::vector<std::uint8_t> bytes;
  transport::CameraFrameView view;
};

TestFrame Frame(const std::string& camera, std::uint64_t seq, double t_s, int value) {
  TestFrame f;
  f.bytes = Jpeg(value);
  f.view.header.set_camera(camera);
  f.view.header.set_encoding("jpeg");
  f.view.header.set_source_seq(seq);
  f.view.header.set_is_key_frame(true);
  f.view.header.mutable_header()->set_capture_stamp_ns(kT0 + static_cast<StampNs>(t_s * 1e9));
  f.view.payload = f.bytes.data();
  f.view.payload_size = f.bytes.size();
  return f;
}

EnginePolicy Policy(const std::string& yaml, std::uint64_t seed) {
  return EnginePolicy(EngineConfig{parse_faults(YAML::Load(yaml), "test"), seed});
}

cv::Mat Decode(const std::vector<std::uint8_t>& bytes) {
  return *codec::decode_jpeg(bytes.data(), bytes.size());
}

TEST(EnginePolicyTest, CorruptionInJpegModeIsReencodedAndDescribed) {
  auto policy = Policy("[{type: motion_blur, severity: 3}]", 9);
  const TestFrame f = Frame("CAM_BACK_LEFT", 31, 0, 100);
  const runtime::FaultDecision d = policy.apply(f.view, nullptr);
  EXPECT_EQ(d.action, msgs::FAULT_ACTION_CORRUPT);
  ASSERT_EQ(d.faults.size(), 1u);
  EXPECT_EQ(d.faults[0].name(), "motion_blur");
  EXPECT_EQ(d.faults[0].severity(), 3u);
  EXPECT_EQ(d.faults[0].seed(), frame_seed(9, 4, 31));
  EXPECT_EQ(d.faults[0].rng(), "fast");
  ASSERT_EQ(d.faults[0].params().count("angle_deg"), 1u);
  EXPECT_LE(std::fabs(d.faults[0].params().at("angle_deg")), 45.0);
  ASSERT_TRUE(d.replacement_jpeg);
  const cv::Mat out = Decode(*d.replacement_jpeg);
  EXPECT_EQ(out.size(), cv::Size(48, 32));
  EXPECT_GT(cv::norm(out, Decode(f.bytes), cv::NORM_INF), 0);
  // Same frame again (fresh policy): identical bytes.
  auto again = Policy("[{type: motion_blur, severity: 3}]", 9);
  EXPECT_EQ(*again.apply(f.view, nullptr).replacement_jpeg, *d.replacement_jpeg);
}

// The injector's jpeg_quality reaches the re-encoder (issue #18: the quality of faulted frames is a
// parameter).
TEST(EnginePolicyTest, JpegQualityOfFaultedFramesIsAParameter) {
  const YAML::Node faults = YAML::Load("[{type: motion_blur, severity: 3}]");
  auto q95 = make_frame_policy(faults, "", 9, "test");
  auto q40 = make_frame_policy(faults, "", 9, "test", 40);
  const TestFrame f = Frame("CAM_FRONT", 3, 0, 100);
  const auto a = q95->apply(f.view, nullptr);
  const auto b = q40->apply(f.view, nullptr);
  ASSERT_TRUE(a.replacement_jpeg && b.replacement_jpeg);
  EXPECT_LT(b.replacement_jpeg->size(), a.replacement_jpeg->size());
  // Same pixels before encoding: q95 is what the default gives.
  auto q95_explicit = make_frame_policy(faults, "", 9, "test", 95);
  EXPECT_EQ(*q95_explicit->apply(f.view, nullptr).replacement_jpeg, *a.replacement_jpeg);
  EXPECT_THROW(make_frame_policy(faults, "", 9, "test", 0), ConfigError);
  EXPECT_THROW(make_frame_policy(faults, "", 9, "test", 101), ConfigError);
}

TEST(EnginePolicyTest, BlackInJpegModeDecodesToZeros) {
  auto policy = Policy("[{type: camera_crash, cameras: all, severity: 5, rng: numpy}]", 0);
  // Seed 0, five draws: at least one camera is dead; find it.
  bool saw_black = false;
  for (int cam = 0; cam < kNumCameras; ++cam) {
    const TestFrame f = Frame(kCameraNames[cam], 1, 0, 60);
    const auto d = policy.apply(f.view, nullptr);
    if (d.action != msgs::FAULT_ACTION_BLACK) {
      EXPECT_FALSE(d.replacement_jpeg);
      continue;
    }
    saw_black = true;
    ASSERT_TRUE(d.replacement_jpeg);
    const cv::Mat out = Decode(*d.replacement_jpeg);
    EXPECT_EQ(out.size(), cv::Size(48, 32));
    EXPECT_EQ(cv::countNonZero(out.reshape(1)), 0);
  }
  EXPECT_TRUE(saw_black);
}

TEST(EnginePolicyTest, FreezeInJpegModeRepeatsTheLastGoodBytes) {
  auto policy = Policy("[{type: freeze, cameras: [CAM_FRONT], start_s: 1}]", 0);
  const TestFrame good = Frame("CAM_FRONT", 1, 0.5, 10);
  EXPECT_EQ(policy.apply(good.view, nullptr).action, msgs::FAULT_ACTION_PASS);
  const TestFrame later = Frame("CAM_FRONT", 2, 1.5, 200);
  const auto d = policy.apply(later.view, nullptr);
  EXPECT_EQ(d.action, msgs::FAULT_ACTION_FREEZE);
  ASSERT_TRUE(d.replacement_jpeg);
  EXPECT_EQ(*d.replacement_jpeg, good.bytes);
}

TEST(EnginePolicyTest, DecodedModeRendersInPlaceAndDropNeedsNoPixels) {
  auto policy =
      Policy("[{type: black, cameras: [CAM_BACK]}, {type: drop, cameras: [CAM_FRONT]}]", 0);
  const TestFrame back = Frame("CAM_BACK", 1, 0, 90);
  cv::Mat image = Decode(back.bytes);
  EXPECT_EQ(policy.apply(back.view, &image).action, msgs::FAULT_ACTION_BLACK);
  EXPECT_EQ(cv::countNonZero(image.reshape(1)), 0);
  const TestFrame front = Frame("CAM_FRONT", 1, 0, 90);
  const auto d = policy.apply(front.view, nullptr);
  EXPECT_EQ(d.action, msgs::FAULT_ACTION_DROP);
  ASSERT_EQ(d.faults.size(), 1u);
  EXPECT_EQ(d.faults[0].name(), "drop");
}

TEST(EnginePolicyTest, MakeFramePolicyAddsTheShorthandAndNamesErrors) {
  EXPECT_NE(
      dynamic_cast<runtime::PassThroughPolicy*>(make_frame_policy(YAML::Node(), "", 0, "fi").get()),
      nullptr);
  auto p =
      make_frame_policy(YAML::Load("[{type: drop, cameras: [CAM_FRONT]}]"), "fog/mid", 3, "fi");
  auto* engine = dynamic_cast<EnginePolicy*>(p.get());
  ASSERT_NE(engine, nullptr);
  ASSERT_EQ(engine->engine().config().faults.size(), 2u);
  EXPECT_EQ(engine->engine().config().faults[1].name(), "fog");
  EXPECT_EQ(engine->engine().config().seed, 3u);
  try {
    (void)make_frame_policy(YAML::Load("[{type: fog, severity: 0}]"), "", 0, "fault_injector");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("fault_injector: faults[0].severity = 0"),
              std::string::npos)
        << e.what();
  }
}

// player -> injector(EnginePolicy) -> test subscriber over ipc: CAM_FRONT crashes in drop mode,
// CAM_BACK gets fog. Dropped frames are not seq gaps downstream and every source frame has its
// FaultEvent.
TEST(InjectorIntegrationTest, DroppedFramesAreEventsNotSeqGaps) {
  char tmpl[] = "/tmp/faultline-policy-XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  ::setenv("FAULTLINE_RUN_DIR", (dir + "/graph").c_str(), 1);
  auto log = logging::make_node_logger("policy_test", "warn");

  std::vector<dataset::CameraFrameRecord> frames;
  std::map<std::string, runtime::ImageBytes> images;
  std::int64_t t_us = 1'600'000'000'000'000;
  const int samples = 4, per_sample = 2;  // one sweep + one key frame per camera
  for (int k = 0; k < samples; ++k) {
    for (int j = 0; j < per_sample; ++j) {
      for (int cam = 0; cam < kNumCameras; ++cam) {
        dataset::CameraFrameRecord f;
        f.channel = kCameraNames[cam];
        f.filename = "img" + std::to_string(frames.size()) + ".jpg";
        f.sample_data_token = "sd-" + f.filename;
        f.sample_token = "sample-" + std::to_string(k);
        f.scene_token = "scene-a";
        f.scene_name = "scene-0001";
        f.is_key_frame = j == per_sample - 1;
        f.timestamp_us = t_us;
        f.width = 48;
        f.height = 32;
        t_us += 1000;
        images[f.filename] = std::make_shared<const std::vector<std::uint8_t>>(
            Jpeg(static_cast<int>(frames.size())));
        frames.push_back(f);
      }
      t_us += 80'000;
    }
  }
  const std::size_t total = frames.size();

  runtime::PlayerConfig pc;
  pc.rate = 0;
  pc.hwm = 1000;
  pc.endpoint = "ipc://" + dir + "/player.sock";
  pc.wait_subscribers = 1;
  SystemClock clock;
  runtime::PlayerLoop player(
      pc, "nusc_player", std::make_unique<runtime::MemoryFrameSource>(frames, images), clock, log);
  runtime::InjectorConfig ic;
  ic.input_endpoints = {player.endpoint()};
  ic.output_endpoint = "ipc://" + dir + "/injector.sock";
  ic.input_hwm = ic.output_hwm = 1000;
  ic.wait_subscribers = 1;
  ic.workers = 3;  // the counts and the seq-gap-free output hold with a worker pool too
  runtime::InjectorLoop injector(
      ic, "fault_injector",
      make_frame_policy(YAML::Load(R"([{type: camera_crash, cameras: [CAM_FRONT], mode: drop},
                                       {type: fog, severity: 2, cameras: [CAM_BACK]}])"),
                        "", 5, "fault_injector"),
      log);
  transport::SubscriberConfig sc;
  sc.endpoints = {injector.output_endpoint()};
  sc.topics = {"/faulty/", "/faultline/faults", "/sync/sample"};
  sc.rcv_hwm = 10000;
  transport::RawSubscriber sub(sc);

  std::atomic<bool> stop{false};
  auto injector_rc = std::async(std::launch::async, [&] { return injector.run(stop); });
  auto player_rc = std::async(std::launch::async, [&] { return player.run(stop); });

  transport::DropCounter drops;
  std::map<std::string, int> frames_per_camera, events_per_camera;
  int dropped_events = 0, corrupt_frames = 0, corrupt_events = 0;
  bool saw_last = false;
  const StampNs deadline = monotonic_now_ns() + 60 * kNsPerSec;  // watchdog, not synchronisation
  while (!saw_last && monotonic_now_ns() < deadline) {
    auto r = sub.receive(50 * kNsPerMs);
    if (!r.is_ok()) continue;
    const std::string topic(r->topic());
    if (topic == "/sync/sample") {
      msgs::SampleBoundary b;
      ASSERT_TRUE(transport::parse_message(*r, &b).is_ok());
      saw_last = b.last_in_run();
    } else if (topic == "/faultline/faults") {
      msgs::FaultEvent e;
      ASSERT_TRUE(transport::parse_message(*r, &e).is_ok());
      ++events_per_camera[e.camera()];
      if (e.state().action() == msgs::FAULT_ACTION_DROP) {
        ++dropped_events;
        EXPECT_EQ(e.camera(), "CAM_FRONT");
        ASSERT_EQ(e.state().faults_size(), 1);
        EXPECT_EQ(e.state().faults(0).name(), "camera_crash");
      }
      if (e.state().action() == msgs::FAULT_ACTION_CORRUPT) ++corrupt_events;
    } else {
      auto view = transport::parse_camera_frame(*r);
      ASSERT_TRUE(view.is_ok()) << view.status().message();
      (void)drops.observe(view->header.header().publisher(), topic, view->header.header().seq());
      ++frames_per_camera[view->header.camera()];
      if (view->header.camera() == "CAM_BACK") {
        EXPECT_EQ(view->header.fault().action(), msgs::FAULT_ACTION_CORRUPT);
        ASSERT_EQ(view->header.fault().faults_size(), 1);
        EXPECT_EQ(view->header.fault().faults(0).name(), "fog");
        EXPECT_EQ(view->header.fault().faults(0).seed(),
                  frame_seed(5, 3, view->header.source_seq(), /*fault_index=*/1));
        const auto decoded = codec::decode_jpeg(view->payload, view->payload_size);
        ASSERT_TRUE(decoded.is_ok());
        EXPECT_EQ(decoded->size(), cv::Size(48, 32));
        ++corrupt_frames;
      }
    }
  }
  stop = true;
  EXPECT_TRUE(saw_last) << "run did not complete";
  EXPECT_EQ(player_rc.get(), 0);
  EXPECT_EQ(injector_rc.get(), 0);

  const int per_camera = samples * per_sample;
  EXPECT_EQ(frames_per_camera.count("CAM_FRONT"), 0u);
  for (int cam = 1; cam < kNumCameras; ++cam)
    EXPECT_EQ(frames_per_camera[kCameraNames[cam]], per_camera);
  for (int cam = 0; cam < kNumCameras; ++cam)
    EXPECT_EQ(events_per_camera[kCameraNames[cam]], per_camera);
  EXPECT_EQ(dropped_events, per_camera);
  EXPECT_EQ(corrupt_frames, per_camera);
  EXPECT_EQ(corrupt_events, per_camera);
  EXPECT_EQ(drops.total().transport_drops, 0u);  // the injector's own seq skips nothing
  EXPECT_EQ(injector.counts().frames_in, total);
  EXPECT_EQ(injector.counts().injected_drops, static_cast<std::uint64_t>(per_camera));
  EXPECT_EQ(injector.counts().frames_out, total - static_cast<std::size_t>(per_camera));
  std::system(("rm -rf " + dir).c_str());
}

}  // namespace
}  // namespace faultline::runtime
