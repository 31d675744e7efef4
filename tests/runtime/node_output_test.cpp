// NodeOutput, the sending side every node loop shares: the seq of each topic, the stamps read from
// the clock, what the topic registry announces, and where the statistics go. The stamping runs
// without any socket; the registry and statistics tests use ipc:// sockets in a scratch directory.
#include "runtime/node_output.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <stdexcept>

#include "common/logging.hpp"
#include "detection.pb.h"
#include "manual_clock.hpp"  // tests/
#include "stats.pb.h"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {
namespace {

constexpr StampNs kStart = 1000 * kNsPerSec;
constexpr StampNs kRealtimeOffset = 1'700'000'000 * kNsPerSec;
constexpr DurationNs kReceiveTimeout = 10 * kNsPerSec;  // a bound for failures, not a measurement

class NodeOutputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-nodeoutput-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    ::setenv("FAULTLINE_RUN_DIR", (dir_ + "/graph").c_str(), 1);
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }

  std::unique_ptr<NodeOutput> Make(const NodeOutputConfig& config) {
    return std::make_unique<NodeOutput>("test_node", config, clock_, log_);
  }
  NodeOutputConfig Pub() const {
    NodeOutputConfig oc;
    oc.publisher.emplace();
    oc.publisher->endpoint = "ipc://" + dir_ + "/out.sock";
    oc.publisher->snd_hwm = 64;
    return oc;
  }
  // The topics this process announced as test_node.
  static std::vector<transport::TopicInfo> Announced() {
    std::vector<transport::TopicInfo> out;
    for (auto& t : transport::list_topics()) {
      if (t.pid == ::getpid() && t.node == "test_node") out.push_back(t);
    }
    return out;
  }

  std::string dir_;
  ManualClock clock_{kStart, kRealtimeOffset};
  std::shared_ptr<spdlog::logger> log_ = logging::make_node_logger("node_output_test", "warn");
};

TEST_F(NodeOutputTest, NumbersEachTopicOnItsOwnAndStampsTheClock) {
  auto out = Make(NodeOutputConfig{});  // stamping needs no socket
  msgs::Header a1, b1, a2;
  out->stamp(&a1, "/a");
  clock_.advance_by(5 * kNsPerMs);
  out->stamp(&b1, "/b");
  out->stamp(&a2, "/a");
  EXPECT_EQ(a1.seq(), 1u);
  EXPECT_EQ(b1.seq(), 1u);
  EXPECT_EQ(a2.seq(), 2u);
  EXPECT_EQ(out->last_seq("/a"), 2u);
  EXPECT_EQ(out->last_seq("/never"), 0u);
  EXPECT_EQ(a1.publisher(), "test_node");
  EXPECT_EQ(a1.publish_mono_ns(), kStart);
  EXPECT_EQ(a1.publish_stamp_ns(), kStart + kRealtimeOffset);
  EXPECT_EQ(b1.publish_mono_ns(), kStart + 5 * kNsPerMs);
  EXPECT_EQ(b1.publish_stamp_ns(), kStart + 5 * kNsPerMs + kRealtimeOffset);
}

TEST_F(NodeOutputTest, AnUnnumberedStampLeavesTheSequenceAlone) {
  auto out = Make(NodeOutputConfig{});
  msgs::Header first, unnumbered, second;
  out->stamp(&first, "/sync/end");
  out->stamp_unnumbered(&unnumbered);
  out->stamp(&second, "/sync/end");
  EXPECT_EQ(unnumbered.seq(), 0u);
  EXPECT_EQ(unnumbered.publisher(), "test_node");
  EXPECT_EQ(unnumbered.publish_mono_ns(), kStart);
  EXPECT_EQ(second.seq(), 2u);
}

TEST_F(NodeOutputTest, WithoutAPublisherOnlyStatisticsRemain) {
  auto out = Make(NodeOutputConfig{});
  EXPECT_FALSE(out->has_publisher());
  EXPECT_THROW(out->publisher(), std::logic_error);
  EXPECT_EQ(out->oversize_refused(), 0u);
  EXPECT_EQ(out->shm_path(), "");
  stats::Sample s;
  s.receive_mono_ns = kStart;
  s.size_bytes = 100;
  out->stats()->record("/detections", "detector", s);
  out->stats()->add_malformed("/detections", 2);
  out->close_stats();  // logs only: there is no socket
  const auto totals = out->stats_totals();
  ASSERT_EQ(totals.size(), 1u);
  EXPECT_EQ(totals[0].topic, "/detections");
  EXPECT_EQ(totals[0].received, 1u);
  EXPECT_EQ(totals[0].malformed, 2u);
}

TEST_F(NodeOutputTest, AnnouncesEachTopicOnceAtItsEndpoint) {
  {
    auto out = Make(Pub());
    EXPECT_TRUE(Announced().empty()) << "nothing before the first announcement";
    out->announce("/cam_front/image_rect_compressed", "faultline.msgs.CameraFrame");
    out->announce("/sync/sample", "faultline.msgs.SampleBoundary");
    out->announce("/cam_front/image_rect_compressed", "faultline.msgs.CameraFrame");
    out->announce_stats();
    auto topics = Announced();
    ASSERT_EQ(topics.size(), 3u);  // sorted by topic
    EXPECT_EQ(topics[0].topic, "/cam_front/image_rect_compressed");
    EXPECT_EQ(topics[0].type, "faultline.msgs.CameraFrame");
    EXPECT_EQ(topics[1].topic, "/statistics");
    EXPECT_EQ(topics[1].type, "faultline.msgs.TopicStats");
    EXPECT_EQ(topics[2].topic, "/sync/sample");
    EXPECT_EQ(topics[2].type, "faultline.msgs.SampleBoundary");
    for (const auto& t : topics) EXPECT_EQ(t.endpoint, out->endpoint()) << t.topic;
  }
  EXPECT_TRUE(Announced().empty()) << "the registry entry goes with the output";
}

TEST_F(NodeOutputTest, StatisticsGoOutOnAPubSocketWithTheirOwnSequence) {
  auto out = Make(Pub());
  transport::SubscriberConfig sc;
  sc.endpoints = {out->endpoint()};
  sc.topics = {"/statistics"};
  transport::RawSubscriber sub(sc);
  ASSERT_TRUE(
      out->publisher().wait_for_subscribers("/statistics", 1, kReceiveTimeout, nullptr).is_ok());
  stats::Sample s;
  s.receive_mono_ns = kStart;
  s.size_bytes = 10;
  out->stats()->record("/cam", "test_node", s);
  out->close_stats();
  auto r = sub.receive(kReceiveTimeout);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(r->topic(), "/statistics");
  msgs::TopicStats ts;
  ASSERT_TRUE(transport::parse_message(*r, &ts).is_ok());
  EXPECT_EQ(ts.topic(), "/cam");
  EXPECT_EQ(ts.received(), 1u);
  EXPECT_EQ(ts.header().seq(), 1u);
  EXPECT_EQ(ts.header().publisher(), "test_node");
  EXPECT_EQ(ts.header().publish_mono_ns(), kStart);
}

TEST_F(NodeOutputTest, APushSocketCarriesNoStatistics) {
  // The sink's shape: its acks PUSH to the player's PULL, which expects acks only.
  transport::SubscriberConfig sc;
  sc.endpoints = {"ipc://" + dir_ + "/acks.sock"};
  sc.pattern = transport::Pattern::PushPull;
  sc.bind = true;
  transport::RawSubscriber acks(sc);
  NodeOutputConfig oc;
  oc.publisher.emplace();
  oc.publisher->endpoint = acks.endpoints().front();
  oc.publisher->bind = false;
  oc.publisher->pattern = transport::Pattern::PushPull;
  oc.publisher->send_timeout_ns = kReceiveTimeout;
  auto out = Make(oc);
  stats::Sample s;
  s.receive_mono_ns = kStart;
  out->stats()->record("/detections", "detector", s);
  out->close_stats();  // a window is due, and it is only logged
  msgs::SampleAck ack;
  ack.set_sample_token("s1");
  out->stamp(ack.mutable_header(), "/sync/ack");
  ASSERT_TRUE(out->send("/sync/ack", ack).is_ok());
  auto r = acks.receive(kReceiveTimeout);  // PUSH keeps order: a TopicStats would come first
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(r->topic(), "/sync/ack");
  msgs::SampleAck got;
  ASSERT_TRUE(transport::parse_message(*r, &got).is_ok());
  EXPECT_EQ(got.sample_token(), "s1");
  EXPECT_EQ(got.header().seq(), 1u);
}

}  // namespace
}  // namespace faultline::runtime
