// Limits and access (#22) of the ROS 2 bridges' ZeroMQ sides: ros2_in's PUB binds beyond loopback
// only with allow_remote and serves CURVE subscribers with the right key (every frame, by seq) but
// not a wrong one (refused, counted); ros2_out's SUB takes every frame from a CURVE publisher with
// the right key and nothing with a wrong one. DDS runs on loopback in a test-only domain, as in
// interop_test.cpp.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <functional>
#include <thread>

#include "camera_frame.pb.h"
#include "codec/jpeg.hpp"
#include "common/config.hpp"
#include "curve_keys.hpp"  // tests/
#include "fastdds_peer.hpp"
#include "fastdds_types/sensor_msgsPubSubTypes.h"
#include "ros2dds/bridge_in.hpp"
#include "ros2dds/bridge_out.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::ros2dds {
namespace {

namespace smsg = sensor_msgs::msg::dds_;
using namespace std::chrono_literals;

constexpr int kFrames = 6;
constexpr const char* kRosTopic = "/test/cam_front/image_raw/compressed";

std::shared_ptr<spdlog::logger> QuietLogger(const std::string& name) {
  return std::make_shared<spdlog::logger>(name, std::make_shared<spdlog::sinks::null_sink_mt>());
}

// Lines of `ring` containing `needle`.
int Count(spdlog::sinks::ringbuffer_sink_mt& ring, const std::string& needle) {
  int n = 0;
  for (const auto& line : ring.last_formatted())
    n += line.find(needle) != std::string::npos ? 1 : 0;
  return n;
}

bool Eventually(const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::yield();
  }
  return true;
}

std::string ThrownMessage(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no ConfigError)";
}

std::vector<std::uint8_t> Jpeg(int i) {
  cv::Mat img(24, 32, CV_8UC3, cv::Scalar(10 * i, 100, 200));
  return codec::encode_jpeg(img, 90).value();
}

class BridgeAccessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    domain_ = 100 + static_cast<int>(::getpid() % 100);
    ::setenv("CYCLONEDDS_URI",
             "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
             "address=\"127.0.0.1\"/>"
             "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
             "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>19</"
             "MaxAutoParticipantIndex>"
             "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>",
             1);
  }
  InBridgeConfig In(const std::string& endpoint) const {
    InBridgeConfig cfg;
    cfg.domain_id = domain_;
    cfg.topics = {kRosTopic};
    cfg.tf_static = false;
    cfg.endpoint = endpoint;
    cfg.stats_log_period_s = 0;
    return cfg;
  }
  transport::SubscriberConfig Sub(const std::string& endpoint, const std::string& key) const {
    transport::SubscriberConfig sc;
    sc.endpoints = {endpoint};
    sc.topics = {"/ros2/"};
    sc.rcv_hwm = 1000;
    sc.access = keys_.client(key);
    return sc;
  }
  int domain_ = 0;
  faultline::test::CurveKeys keys_;
};

TEST_F(BridgeAccessTest, Ros2InBindsBeyondLoopbackOnlyWithAllowRemote) {
  InBridgeConfig cfg = In("tcp://0.0.0.0:*");
  const std::string what =
      ThrownMessage([&] { InBridge b(cfg, "ros2_in", QuietLogger("ros2_in")); });
  EXPECT_NE(what.find("endpoint = tcp://0.0.0.0:*"), std::string::npos) << what;
  EXPECT_NE(what.find("allow_remote"), std::string::npos) << what;
  cfg.access.allow_remote = true;
  InBridge allowed(cfg, "ros2_in", QuietLogger("ros2_in"));
  EXPECT_EQ(allowed.endpoint().rfind("tcp://0.0.0.0:", 0), 0u);
}

TEST_F(BridgeAccessTest, Ros2InServesTheRightKeyEveryFrameAndRefusesAWrongKey) {
  InBridgeConfig cfg = In("tcp://127.0.0.1:*");
  cfg.access = keys_.server();
  InBridge bridge(cfg, "ros2_in", QuietLogger("ros2_in"));
  transport::RawSubscriber good(Sub(bridge.endpoint(), "good"));
  transport::RawSubscriber bad(Sub(bridge.endpoint(), "bad"));
  ASSERT_TRUE(Eventually([&] {
    (void)bad.receive(10 * kNsPerMs);
    return bridge.auth_refused() >= 1 && bad.handshake_failures() >= 1;
  }));
  std::atomic<bool> stop{false};
  int rc = -1;
  std::thread runner([&] { rc = bridge.run(stop); });

  test::FastPeer peer(domain_);
  auto* writer = peer.writer<smsg::CompressedImage_PubSubType>(std::string("rt") + kRosTopic, {});
  ASSERT_TRUE(test::FastPeer::wait_matched(writer, 1, 30s)) << "Cyclone reader never matched";
  for (int i = 0; i < kFrames; ++i) {
    smsg::CompressedImage_ image;
    image.header().stamp().sec(1533151603 + i);
    image.header().frame_id("cam_front");
    image.format("jpeg");
    image.data(Jpeg(i));
    ASSERT_TRUE(writer->write(&image));
    ASSERT_EQ(writer->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(30, 0)),
              ReturnCode_t::RETCODE_OK);
  }
  for (int seq = 1; seq <= kFrames; ++seq) {
    auto r = good.receive(30 * kNsPerSec);
    ASSERT_TRUE(r.is_ok()) << "frame " << seq << ": " << r.status().to_string();
    auto view = transport::parse_camera_frame(*r);
    ASSERT_TRUE(view) << view.status().message();
    EXPECT_EQ(view->header.header().seq(), static_cast<std::uint64_t>(seq));
  }
  stop = true;
  runner.join();
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(bad.receive(100 * kNsPerMs).status().code(), StatusCode::kWouldBlock);
  EXPECT_EQ(bridge.auth_refused(), 1u);
  EXPECT_EQ(good.handshake_failures(), 0u);
}

TEST_F(BridgeAccessTest, Ros2OutTakesEveryFrameWithTheRightKeyAndNothingWithAWrongKey) {
  transport::PublisherConfig pc;
  pc.endpoint = "tcp://127.0.0.1:*";
  pc.snd_hwm = 1000;
  pc.zero_copy = false;  // each JPEG lives only for its send
  pc.access = keys_.server();
  transport::Publisher injector(pc);  // stands in for the fault injector's output
  auto out_config = [&](const std::string& key) {
    OutBridgeConfig cfg;
    cfg.domain_id = domain_;
    cfg.input_endpoints = {injector.endpoint()};
    cfg.stats_log_period_s = 0;
    cfg.access = keys_.client(key);
    return cfg;
  };
  // The bad bridge's own lines (its stop line), and the transport's (the refusal, logged through
  // the process's node logger: spdlog's default here).
  auto bad_lines = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(64);
  bad_lines->set_pattern("%v");
  auto transport_lines = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(64);
  transport_lines->set_pattern("%v");
  spdlog::default_logger()->sinks().push_back(transport_lines);
  OutBridge good(out_config("good"), "ros2_out", QuietLogger("ros2_out_good"));
  OutBridge bad(out_config("bad"), "ros2_out",
                std::make_shared<spdlog::logger>("ros2_out_bad", bad_lines));
  std::atomic<bool> stop{false};
  int good_rc = -1, bad_rc = -1;
  std::thread good_runner([&] { good_rc = good.run(stop); });
  std::thread bad_runner([&] { bad_rc = bad.run(stop); });
  const std::string topic = "/faulty/cam_front/image_rect_compressed";
  ASSERT_TRUE(injector.wait_for_subscribers(topic, 1, 30 * kNsPerSec).is_ok());
  ASSERT_TRUE(Eventually([&] { return injector.auth_refused() >= 1; }));
  for (int i = 0; i < kFrames; ++i) {
    const std::vector<std::uint8_t> jpeg = Jpeg(i);
    msgs::CameraFrame f;
    f.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
    f.mutable_header()->set_publisher("fault_injector");
    f.mutable_header()->set_frame_id("cam_front");
    f.set_camera("CAM_FRONT");
    f.set_encoding("jpeg");
    f.set_width(32);
    f.set_height(24);
    f.set_payload_bytes(static_cast<std::uint32_t>(jpeg.size()));
    transport::Payload p;
    p.data = jpeg.data();
    p.size_bytes = jpeg.size();
    ASSERT_TRUE(injector.send(topic, f.SerializeAsString(), p).is_ok());
  }
  ASSERT_TRUE(Eventually([&] { return good.counts().frames_in.load() >= kFrames; }));
  // Counted when logged: wait for the line, so the stop line's count is exact.
  const bool refusal_seen = Eventually([&] {
    return Count(*transport_lines, "refused by the publisher at " + injector.endpoint()) >= 1;
  });
  stop = true;
  good_runner.join();
  bad_runner.join();
  auto& default_sinks = spdlog::default_logger()->sinks();
  default_sinks.erase(std::remove(default_sinks.begin(), default_sinks.end(), transport_lines),
                      default_sinks.end());
  EXPECT_TRUE(refusal_seen);
  // ros2_out's stop line says why it took nothing, as the other nodes' counts do.
  EXPECT_EQ(Count(*bad_lines, "stopped: frames_in=0 "), 1);
  EXPECT_EQ(Count(*bad_lines, " handshake_failures=1 refused_by_peer=1"), 1)
      << (bad_lines->last_formatted().empty() ? "" : bad_lines->last_formatted().back());
  EXPECT_EQ(good_rc, 0);
  EXPECT_EQ(good.counts().frames_in.load(), static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(good.counts().transport_drops.load(), 0u);
  EXPECT_EQ(bad.counts().frames_in.load(), 0u);
  EXPECT_EQ(injector.subscriber_count(topic), 1);  // the refused bridge never subscribed
  EXPECT_EQ(injector.auth_refused(), 1u);
}

}  // namespace
}  // namespace faultline::ros2dds
