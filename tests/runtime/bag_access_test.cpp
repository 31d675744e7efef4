// Limits and access (#22) of the recorder and `bag play`: CURVE keys from files admit the right
// peer (every message arrives, counted by seq) and refuse a wrong one (nothing arrives; the binding
// side counts it), and the player binds beyond loopback only with allow_remote.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <functional>
#include <string>
#include <thread>

#include "camera_frame.pb.h"
#include "common/clock.hpp"
#include "common/config.hpp"
#include "curve_keys.hpp"  // tests/
#include "runtime/bag_player.hpp"
#include "runtime/bag_recorder.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {
namespace {

constexpr const char* kTopic = "/sync/sample";
constexpr int kMessages = 10;

std::shared_ptr<spdlog::logger> QuietLogger() {
  return std::make_shared<spdlog::logger>("bag_access_test",
                                          std::make_shared<spdlog::sinks::null_sink_mt>());
}

// Spins (yielding) until done() or 30 s; the bound only turns a hang into a failure.
bool Eventually(const std::function<bool()>& done) {
  const StampNs deadline = monotonic_now_ns() + 30 * kNsPerSec;
  while (!done()) {
    if (monotonic_now_ns() > deadline) return false;
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

class BagAccessTest : public ::testing::Test {
 protected:
  RecorderConfig Recorder(const std::string& name, transport::AccessConfig access,
                          const std::string& endpoint) {
    RecorderConfig cfg;
    cfg.output = keys_.dir() + "/" + name + ".mcap";
    cfg.topics = {kTopic};
    cfg.endpoints = {endpoint};
    cfg.foxglove_view = false;
    cfg.access = std::move(access);
    return cfg;
  }

  // Sends SampleBoundaries with seq 1..kMessages.
  static void SendAll(transport::Publisher& pub) {
    for (int seq = 1; seq <= kMessages; ++seq) {
      msgs::SampleBoundary b;
      b.mutable_header()->set_seq(static_cast<std::uint64_t>(seq));
      b.mutable_header()->set_publisher("test_pub");
      b.set_sample_token("sample" + std::to_string(seq));
      ASSERT_TRUE(pub.send(kTopic, b.SerializeAsString()).is_ok());
    }
  }

  // A CURVE publisher (server key, only "good" allowed) recorded by a recorder with the "good" key
  // and one with the "bad" key; returns the good bag's path.
  std::string RecordWithBothKeys() {
    transport::PublisherConfig pc;
    pc.endpoint = "tcp://127.0.0.1:*";
    pc.access = keys_.server();
    pc.snd_hwm = 1000;
    transport::Publisher pub(pc);
    BagRecorder good(Recorder("good", keys_.client("good"), pub.endpoint()), QuietLogger());
    BagRecorder bad(Recorder("bad", keys_.client("bad"), pub.endpoint()), QuietLogger());
    std::atomic<bool> stop{false};
    int good_rc = -1, bad_rc = -1;
    std::thread good_thread([&] { good_rc = good.run(stop); });
    std::thread bad_thread([&] { bad_rc = bad.run(stop); });
    EXPECT_TRUE(pub.wait_for_subscribers(kTopic, 1, 30 * kNsPerSec).is_ok());
    EXPECT_TRUE(Eventually(
        [&] { return pub.auth_refused() >= 1; }));  // the bad recorder, counted and logged
    SendAll(pub);
    EXPECT_TRUE(Eventually([&] { return good.recorded() >= kMessages; }));
    stop = true;
    good_thread.join();
    bad_thread.join();
    EXPECT_EQ(good_rc, 0);
    EXPECT_EQ(bad_rc, 0);
    EXPECT_EQ(good.counts().messages, static_cast<std::uint64_t>(kMessages));
    EXPECT_EQ(good.drops().total().transport_drops, 0u);
    EXPECT_EQ(good.drops().total().received, static_cast<std::uint64_t>(kMessages));
    EXPECT_EQ(bad.counts().messages, 0u);
    EXPECT_EQ(pub.subscriber_count(kTopic), 1);  // the refused recorder never subscribed
    EXPECT_EQ(pub.auth_refused(), 1u);
    return keys_.dir() + "/good.mcap";
  }

  test::CurveKeys keys_;
};

TEST_F(BagAccessTest, RecorderWithTheRightKeyRecordsEveryMessageAndAWrongKeyIsRefused) {
  RecordWithBothKeys();
}

TEST_F(BagAccessTest, PlayerServesTheRightKeyEveryMessageAndRefusesAWrongKey) {
  const std::string bag = RecordWithBothKeys();
  BagPlayerConfig cfg;
  cfg.files = {bag};
  cfg.rate = 0;
  cfg.endpoint = "tcp://127.0.0.1:*";
  cfg.wait_subscribers = 1;
  cfg.wait_timeout_ms = 30000;
  cfg.access = keys_.server();
  BagPlayer player(cfg, QuietLogger());
  auto subscriber = [&](const std::string& name) {
    transport::SubscriberConfig sc;
    sc.endpoints = {player.endpoint()};
    sc.topics = {kTopic};
    sc.rcv_hwm = 1000;
    sc.access = keys_.client(name);
    return transport::RawSubscriber(sc);
  };
  transport::RawSubscriber good = subscriber("good");
  transport::RawSubscriber bad = subscriber("bad");
  ASSERT_TRUE(Eventually([&] {
    (void)bad.receive(10 * kNsPerMs);
    return player.auth_refused() >= 1 && bad.handshake_failures() >= 1;
  }));
  std::atomic<bool> stop{false};
  int rc = -1;
  std::thread runner([&] { rc = player.run(stop); });
  for (int seq = 1; seq <= kMessages; ++seq) {
    auto r = good.receive(30 * kNsPerSec);
    ASSERT_TRUE(r.is_ok()) << "seq " << seq << ": " << r.status().to_string();
    msgs::SampleBoundary b;
    ASSERT_TRUE(transport::parse_message(*r, &b).is_ok());
    EXPECT_EQ(b.header().seq(), static_cast<std::uint64_t>(seq));
  }
  runner.join();
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(player.counts().messages_sent, static_cast<std::uint64_t>(kMessages));
  EXPECT_EQ(bad.receive(100 * kNsPerMs).status().code(), StatusCode::kWouldBlock);
  EXPECT_EQ(player.auth_refused(), 1u);
}

TEST_F(BagAccessTest, PlayerBindsBeyondLoopbackOnlyWithAllowRemote) {
  BagPlayerConfig cfg;
  cfg.files = {keys_.dir() +
               "/never_read.mcap"};  // sockets bind in the constructor; bags open in run()
  cfg.endpoint = "tcp://0.0.0.0:*";
  std::string what = ThrownMessage([&] { BagPlayer p(cfg, QuietLogger()); });
  EXPECT_NE(what.find("endpoint = tcp://0.0.0.0:*"), std::string::npos) << what;
  EXPECT_NE(what.find("allow_remote"), std::string::npos) << what;
  cfg.endpoint = "tcp://127.0.0.1:*";
  cfg.lockstep = true;
  cfg.ack_endpoint = "tcp://*:*";
  what = ThrownMessage([&] { BagPlayer p(cfg, QuietLogger()); });
  EXPECT_NE(what.find("tcp://*:*"), std::string::npos) << what;
  cfg.lockstep = false;
  cfg.control_endpoint = "tcp://0.0.0.0:*";
  what = ThrownMessage([&] { BagPlayer p(cfg, QuietLogger()); });
  EXPECT_NE(what.find("tcp://0.0.0.0:*"), std::string::npos) << what;
  cfg.access.allow_remote = true;
  BagPlayer allowed(cfg, QuietLogger());
  EXPECT_EQ(allowed.control_endpoint().rfind("tcp://0.0.0.0:", 0), 0u);
}

}  // namespace
}  // namespace faultline::runtime
