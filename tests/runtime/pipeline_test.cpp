// player -> injector -> fake detector -> sink as loops in threads over tcp loopback and ipc, with
// ready handshakes (wait for subscribers, lockstep acks) and bounded timeouts instead of sleeps.
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <fstream>
#include <future>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <thread>

#include "camera_frame.pb.h"
#include "common/logging.hpp"
#include "fake_detector.hpp"
#include "runtime/injector_loop.hpp"
#include "runtime/player_loop.hpp"
#include "runtime/sink_loop.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {
namespace {

const char* const kCameras[] = {"CAM_FRONT", "CAM_FRONT_RIGHT", "CAM_FRONT_LEFT",
                                "CAM_BACK",  "CAM_BACK_LEFT",   "CAM_BACK_RIGHT"};

ImageBytes TinyJpeg(int value) {
  cv::Mat img(18, 32, CV_8UC3, cv::Scalar(value, 255 - value, 128));
  std::vector<std::uint8_t> bytes;
  cv::imencode(".jpg", img, bytes);
  return std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes));
}

// `samples` key-frame samples; before each key frame every camera has `sweeps` sweeps.
struct Scenario {
  std::vector<dataset::CameraFrameRecord> frames;
  std::map<std::string, ImageBytes> images;
};

Scenario MakeScenario(int samples, int sweeps) {
  Scenario s;
  std::int64_t t = 1'600'000'000'000'000;
  int n = 0;
  for (int k = 0; k < samples; ++k) {
    for (int j = 0; j <= sweeps; ++j) {
      const bool key = j == sweeps;
      for (const char* cam : kCameras) {
        dataset::CameraFrameRecord f;
        f.channel = cam;
        f.filename = "img" + std::to_string(n++) + ".jpg";
        f.sample_data_token = "sd-" + f.filename;
        f.sample_token = "sample-" + std::to_string(k);
        f.scene_token = "scene-a";
        f.scene_name = "scene-0001";
        f.is_key_frame = key;
        f.timestamp_us = t;
        f.width = 32;
        f.height = 18;
        t += 1000;
        s.images[f.filename] = TinyJpeg(n % 200);
        s.frames.push_back(f);
      }
      t += 80'000;
    }
  }
  return s;
}

std::string TempDir() {
  char tmpl[] = "/tmp/faultline-pipeline-XXXXXX";
  return ::mkdtemp(tmpl);
}

rapidjson::Document ReadJson(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  rapidjson::Document doc;
  doc.Parse<rapidjson::kParseNanAndInfFlag>(ss.str().c_str());
  return doc;
}

struct PipelineParams {
  std::string transport;  // "tcp" or "ipc"
};

class PipelineTest : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    dir_ = TempDir();
    ::setenv("FAULTLINE_RUN_DIR", (dir_ + "/graph").c_str(), 1);
    log_ = logging::make_node_logger("pipeline_test", "warn");
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }
  std::string Endpoint(const std::string& name) const {
    if (GetParam() == "tcp") return "tcp://127.0.0.1:*";
    return "ipc://" + dir_ + "/" + name + ".sock";
  }
  // Unpaced, no lockstep, waits for one subscriber.
  PlayerConfig UnpacedPlayer() const {
    PlayerConfig pc;
    pc.rate = 0;
    pc.hwm = 64;
    pc.endpoint = Endpoint("player");
    pc.wait_subscribers = 1;
    return pc;
  }
  std::string dir_;
  std::shared_ptr<spdlog::logger> log_;
};

TEST_P(PipelineTest, LockstepRunDeliversEveryFrameAndWritesAllSamples) {
  Scenario sc = MakeScenario(/*samples=*/3, /*sweeps=*/2);  // 54 frames
  sc.images.erase(sc.frames[7].filename);                   // a missing file: skipped by the player
  sc.images[sc.frames[10].filename] =
      std::make_shared<const std::vector<std::uint8_t>>(500, 0x42);  // not a JPEG

  PlayerConfig pc;
  pc.rate = 0;
  pc.lockstep = true;
  pc.hwm = 64;
  pc.endpoint = Endpoint("player");
  pc.ack_endpoint = Endpoint("ack");
  pc.wait_subscribers = 1;
  pc.ack_timeout_ms = 20000;
  SystemClock clock;
  PlayerLoop player(pc, "nusc_player", std::make_unique<MemoryFrameSource>(sc.frames, sc.images),
                    clock, log_);

  InjectorConfig ic;
  ic.input_endpoints = {player.endpoint()};
  ic.output_endpoint = Endpoint("injector");
  ic.input_hwm = ic.output_hwm = 64;
  ic.decode = true;
  ic.wait_subscribers = 2;  // sink + detector on /sync/sample
  InjectorLoop injector(ic, "fault_injector", std::make_unique<PassThroughPolicy>(), log_);

  SinkConfig kc;
  kc.detections_endpoint = Endpoint("sink");
  kc.sync_endpoints = {injector.output_endpoint()};
  kc.output = dir_ + "/results.json";
  kc.lockstep = true;
  kc.ack_endpoint = player.ack_endpoint();
  kc.meta = {{"scenario", "pipeline_test"}};
  SinkLoop sink(kc, "detection_sink", log_);
  testing::FakeDetector detector(injector.output_endpoint(), sink.detections_endpoint());

  std::atomic<bool> stop{false};
  auto sink_rc = std::async(std::launch::async, [&] { return sink.run(stop); });
  auto detector_result = std::async(std::launch::async, [&] { return detector.run(stop); });
  auto injector_rc = std::async(std::launch::async, [&] { return injector.run(stop); });
  auto player_rc = std::async(std::launch::async, [&] { return player.run(stop); });
  // Watchdog: a hang fails the test instead of blocking it.
  if (player_rc.wait_for(std::chrono::seconds(60)) != std::future_status::ready ||
      sink_rc.wait_for(std::chrono::seconds(30)) != std::future_status::ready) {
    stop = true;
    ADD_FAILURE() << "pipeline did not finish";
  }
  const int prc = player_rc.get(), irc = injector_rc.get(), src = sink_rc.get();
  stop = true;
  const testing::FakeDetectorResult det = detector_result.get();
  EXPECT_EQ(prc, 0);
  EXPECT_EQ(irc, 0);
  EXPECT_EQ(src, 0);

  EXPECT_EQ(player.counts().frames_sent, 53u);
  EXPECT_EQ(player.counts().missing_images, 1u);
  EXPECT_EQ(player.counts().boundaries_sent, 3u);
  EXPECT_EQ(player.counts().ack_timeouts, 0u);
  EXPECT_EQ(injector.counts().frames_in, 53u);
  EXPECT_EQ(injector.counts().corrupt_jpeg, 1u);
  EXPECT_EQ(injector.counts().injected_drops,
            0u);  // undecodable input is bad input, not an injected fault
  EXPECT_EQ(injector.counts().frames_out, 52u);
  EXPECT_EQ(injector.counts().transport_drops, 0u);
  EXPECT_EQ(injector.counts().boundaries, 3u);
  // Replayed frames carry dataset time: no age is computed from it (#22 item 7: it read ~2.6e11
  // ms).
  for (const auto& w : injector.stats_totals()) {
    EXPECT_GT(w.received, 0u) << w.topic;
    EXPECT_EQ(w.age_ms.count, 0u) << w.topic;
  }
  EXPECT_EQ(det.frames, 52u);
  EXPECT_EQ(det.transport_drops, 0u);  // the injector's own seq has no gap for its dropped frame
  EXPECT_EQ(det.malformed, 0u);
  EXPECT_EQ(det.frames_per_topic.count("/faulty/cam_front/image_raw"), 1u);
  EXPECT_EQ(sink.counts().detection_arrays, 3u);
  EXPECT_EQ(sink.counts().acks_sent, 3u);

  const auto doc = ReadJson(kc.output);
  ASSERT_TRUE(doc.IsObject());
  EXPECT_STREQ(doc["meta"]["scenario"].GetString(), "pipeline_test");
  EXPECT_STREQ(doc["meta"]["faultline_detector"].GetString(), "fake_detector");
  ASSERT_EQ(doc["results"].MemberCount(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(doc["results"][("sample-" + std::to_string(k)).c_str()].Size(), 1u);
  }
  EXPECT_NE(::access((kc.output + ".journal").c_str(), F_OK), 0)
      << "journal removed after a complete run";
}

TEST_P(PipelineTest, SamplesWithoutDetectionsGetEmptyListsOnShutdown) {
  Scenario sc = MakeScenario(2, 1);
  SystemClock clock;
  PlayerLoop player(UnpacedPlayer(), "nusc_player",
                    std::make_unique<MemoryFrameSource>(sc.frames, sc.images), clock, log_);
  SinkConfig kc;
  kc.detections_endpoint = Endpoint("sink");
  kc.sync_endpoints = {player.endpoint()};
  kc.output = dir_ + "/results.json";
  kc.finalize_grace_ms = 0;
  SinkLoop sink(kc, "detection_sink", log_);
  std::atomic<bool> stop{false};
  auto sink_rc = std::async(std::launch::async, [&] { return sink.run(stop); });
  EXPECT_EQ(player.run(stop), 0);
  ASSERT_EQ(sink_rc.wait_for(std::chrono::seconds(30)), std::future_status::ready);
  EXPECT_EQ(sink_rc.get(), 0);
  const auto doc = ReadJson(kc.output);
  ASSERT_TRUE(doc.IsObject());
  ASSERT_EQ(doc["results"].MemberCount(), 2u);
  EXPECT_EQ(doc["results"]["sample-0"].Size(), 0u);
  EXPECT_EQ(doc["results"]["sample-1"].Size(), 0u);
}

// Sweeps recorded after a run's last key frame come after its last_in_run boundary; the injector
// still corrupts and forwards them, then the stream end, and only then stops.
TEST_P(PipelineTest, TrailingSweepsAfterTheLastSampleReachTheInjectorOutput) {
  Scenario sc = MakeScenario(/*samples=*/2, /*sweeps=*/1);  // 24 frames
  std::int64_t t = sc.frames.back().timestamp_us + 80'000;
  for (int j = 0; j < 2; ++j) {  // two trailing sweeps per camera, after sample-1's key frames
    for (const char* cam : kCameras) {
      dataset::CameraFrameRecord f = sc.frames.back();
      f.channel = cam;
      f.filename = "trailing" + std::to_string(j) + cam + ".jpg";
      f.sample_data_token = "sd-" + f.filename;
      f.is_key_frame = false;
      f.timestamp_us = t;
      t += 1000;
      sc.images[f.filename] = TinyJpeg(50 + j);
      sc.frames.push_back(f);
    }
    t += 80'000;
  }
  const std::size_t total = sc.frames.size();  // 36

  SystemClock clock;
  PlayerLoop player(UnpacedPlayer(), "nusc_player",
                    std::make_unique<MemoryFrameSource>(sc.frames, sc.images), clock, log_);
  InjectorConfig ic;
  ic.input_endpoints = {player.endpoint()};
  ic.output_endpoint = Endpoint("injector");
  ic.input_hwm = ic.output_hwm = 64;
  ic.wait_subscribers = 1;
  InjectorLoop injector(ic, "fault_injector", std::make_unique<PassThroughPolicy>(), log_);
  transport::SubscriberConfig oc;
  oc.endpoints = {injector.output_endpoint()};
  oc.topics = {"/faulty/", "/sync/"};
  oc.rcv_hwm = 1000;
  transport::RawSubscriber out(oc);

  std::atomic<bool> stop{false};
  auto injector_rc = std::async(std::launch::async, [&] { return injector.run(stop); });
  auto player_rc = std::async(std::launch::async, [&] { return player.run(stop); });
  std::vector<std::string> seen;  // "F" frame, "B" boundary, "L" last boundary, "E" stream end
  const StampNs deadline = monotonic_now_ns() + 30 * kNsPerSec;
  while (monotonic_now_ns() < deadline && (seen.empty() || seen.back() != "E")) {
    auto r = out.receive(50 * kNsPerMs);
    if (!r.is_ok()) continue;
    const std::string topic(r->topic());
    if (topic == "/sync/end") {
      msgs::StreamEnd e;
      ASSERT_TRUE(transport::parse_message(*r, &e).is_ok());
      EXPECT_EQ(e.frames_sent(), total);
      seen.push_back("E");
    } else if (topic == "/sync/sample") {
      msgs::SampleBoundary b;
      ASSERT_TRUE(transport::parse_message(*r, &b).is_ok());
      EXPECT_EQ(b.stream_end_follows(), b.last_in_run());
      seen.push_back(b.last_in_run() ? "L" : "B");
    } else {
      seen.push_back("F");
    }
  }
  ASSERT_EQ(injector_rc.wait_for(std::chrono::seconds(10)), std::future_status::ready)
      << "injector did not stop";
  stop = true;
  EXPECT_EQ(player_rc.get(), 0);
  EXPECT_EQ(injector_rc.get(), 0);
  EXPECT_EQ(injector.counts().frames_in, total);
  EXPECT_EQ(injector.counts().frames_out, total);
  EXPECT_EQ(injector.counts().stream_ends, 1u);
  // 12 frames, boundary, 12 frames, last boundary, the 12 trailing sweeps, end.
  std::string order;
  for (const auto& s : seen) order += s;
  EXPECT_EQ(order,
            std::string(12, 'F') + "B" + std::string(12, 'F') + "L" + std::string(12, 'F') + "E");
}

INSTANTIATE_TEST_SUITE_P(Transports, PipelineTest, ::testing::Values("tcp", "ipc"));

}  // namespace
}  // namespace faultline::runtime
