// The sink's refusals through its real loop: boxes and arrays the scorer would reject are counted,
// logged once each with the scorer's reason, and left out of results.json. The sink's lockstep ack
// tells the test when an array was handled (bounded waits, no sleeps).
#include "runtime/sink_loop.hpp"

#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <future>
#include <sstream>
#include <thread>

#include "common/config.hpp"
#include "detection.pb.h"
#include "manual_clock.hpp"  // tests/
#include "scoring/submission.hpp"
#include "transport/context.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {
namespace {

class SinkLoopTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-sinkloop-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    ring_ = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(512);
    ring_->set_pattern("%l %v");
    log_ = std::make_shared<spdlog::logger>("sink_loop_test", ring_);
    log_->set_level(spdlog::level::info);
    config_.detections_endpoint = "ipc://" + dir_ + "/det.sock";
    config_.sync_endpoints = {};
    config_.output = dir_ + "/results.json";
    config_.lockstep = true;
    config_.ack_endpoint = "ipc://" + dir_ + "/ack.sock";
    config_.stats_log_period_s = 1000;
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }

  static msgs::DetectionArray Array(const std::string& token, int boxes) {
    msgs::DetectionArray d;
    d.set_sample_token(token);
    d.set_detector("unit");
    for (int i = 0; i < boxes; ++i) {
      auto* b = d.add_detections();
      for (double v : {1.0 + i, 2.0, 3.0}) b->add_translation(v);
      for (double v : {1.5, 4.0, 1.7}) b->add_size(v);
      for (double v : {1.0, 0.0, 0.0, 0.0}) b->add_rotation(v);
      for (double v : {0.0, 0.0}) b->add_velocity(v);
      b->set_detection_name("car");
      b->set_detection_score(0.5);
      b->set_attribute_name("vehicle.moving");
    }
    return d;
  }

  // Runs the sink, sends each array and waits for its ack, then stops the sink.
  void Run(const std::vector<msgs::DetectionArray>& arrays) {
    transport::SubscriberConfig ac;
    ac.endpoints = {config_.ack_endpoint};
    ac.pattern = transport::Pattern::PushPull;
    ac.bind = true;
    transport::RawSubscriber acks(ac);
    SinkLoop sink(config_, "detection_sink", log_);
    transport::PublisherConfig pc;
    pc.endpoint = sink.detections_endpoint();
    pc.pattern = transport::Pattern::PushPull;
    pc.bind = false;
    pc.send_timeout_ns = 10 * kNsPerSec;
    pc.linger_ms = 200;
    transport::Publisher push(pc);
    std::atomic<bool> stop{false};
    auto rc = std::async(std::launch::async, [&] { return sink.run(stop); });
    for (const auto& a : arrays) {
      ASSERT_TRUE(transport::send_message(push, "/detections", a).is_ok());
      auto ack = acks.receive(10 * kNsPerSec);
      if (!ack.is_ok()) {
        stop = true;
        rc.wait();
        FAIL() << "no ack for " << a.sample_token() << ": " << ack.status().message();
      }
    }
    stop = true;
    ASSERT_EQ(rc.wait_for(std::chrono::seconds(30)), std::future_status::ready);
    EXPECT_EQ(rc.get(), 0);
    counts_ = sink.counts();
  }

  // Formatted log lines ("<level> <message>") that contain `fragment`.
  std::vector<std::string> Lines(const std::string& fragment) const {
    std::vector<std::string> out;
    for (const auto& line : ring_->last_formatted()) {
      if (line.find(fragment) != std::string::npos) out.push_back(line);
    }
    return out;
  }

  rapidjson::Document Results() const {
    std::ifstream in(config_.output);
    std::stringstream ss;
    ss << in.rdbuf();
    rapidjson::Document doc;
    doc.Parse<rapidjson::kParseNanAndInfFlag>(ss.str().c_str());
    EXPECT_FALSE(doc.HasParseError());
    auto sub = scoring::parse_submission(ss.str(), config_.output, scoring::SubmissionScope{});
    EXPECT_TRUE(sub.is_ok()) << sub.status().message();  // what the scorer reads
    return doc;
  }

  std::string dir_;
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> ring_;
  std::shared_ptr<spdlog::logger> log_;
  SinkConfig config_;
  SinkCounts counts_;
};

TEST_F(SinkLoopTest, RefusesWhatTheScorerRejectsCountsAndLogsItOnce) {
  auto s1 = Array("s1", 3);
  s1.mutable_detections(1)->set_detection_score(NAN);
  Run({s1, Array("s2", 501)});
  EXPECT_EQ(counts_.detection_arrays, 2u);
  EXPECT_EQ(counts_.rejected_boxes, 1u);
  EXPECT_EQ(counts_.rejected_arrays, 1u);
  const auto nan = Lines("results['s1'][1]: 'detection_score' is NaN");
  ASSERT_EQ(nan.size(), 1u);
  EXPECT_EQ(nan[0].rfind("warning refused box: ", 0), 0u) << nan[0];
  const auto many =
      Lines("results['s2']: Error: Only <= 500 boxes per sample allowed! (found 501)");
  ASSERT_EQ(many.size(), 1u);
  EXPECT_EQ(many[0].rfind("warning refused DetectionArray: ", 0), 0u) << many[0];
  EXPECT_EQ(Lines("1 boxes and 1 arrays refused").size(), 1u);  // the closing line
  const auto doc = Results();
  EXPECT_EQ(doc["results"]["s1"].Size(), 2u);
  EXPECT_FALSE(doc["results"].HasMember("s2"));
  EXPECT_EQ(doc["meta"]["faultline_sink_rejected_boxes"].GetUint64(), 1u);
  EXPECT_EQ(doc["meta"]["faultline_sink_rejected_arrays"].GetUint64(), 1u);
}

TEST_F(SinkLoopTest, ManyRefusalsGoToDebugAfterTheFirstTwentyButAreAllCounted) {
  auto bad = Array("s1", 25);
  for (auto& b : *bad.mutable_detections()) b.set_detection_name("Car");
  Run({bad});
  EXPECT_EQ(counts_.rejected_boxes, 25u);
  EXPECT_EQ(Lines("warning refused box: results['s1']").size(), 20u);
  EXPECT_EQ(Lines("further ones at debug level").size(), 1u);
  EXPECT_EQ(Results()["results"]["s1"].Size(), 0u);
}

TEST_F(SinkLoopTest, UnreadableJournalLinesAreReportedAndCountedInTheMeta) {
  std::ofstream(config_.output + ".journal")
      << R"({"kind":"run","run":{}})"
      << "\n"
      << R"({"kind":"sample","sample_token":"s0"})"
      << "\n"
      << R"({"kind":"detections","sample_token":"s9","bo)";  // torn by a crash
  Run({Array("s1", 1)});
  EXPECT_EQ(counts_.recovered_lines, 1u);
  EXPECT_EQ(counts_.bad_journal_lines, 1u);
  const auto warned = Lines("1 lines could not be read back and were skipped (first: line 3:");
  ASSERT_EQ(warned.size(), 1u);
  EXPECT_EQ(warned[0].rfind("warning journal ", 0), 0u) << warned[0];
  const auto doc = Results();
  EXPECT_EQ(doc["meta"]["faultline_sink_bad_journal_lines"].GetUint64(), 1u);
  EXPECT_TRUE(doc["results"].HasMember("s0"));
  EXPECT_TRUE(doc["results"].HasMember("s1"));
}

TEST_F(SinkLoopTest, JournalOfAnotherRunStopsTheSinkAtStart) {
  std::ofstream(config_.output + ".journal") << R"({"kind":"run","run":{"corruption":"clean"}})"
                                             << "\n"
                                             << R"({"kind":"sample","sample_token":"s0"})"
                                             << "\n";
  config_.run = {{"corruption", "camera_crash/hard"}};
  SinkLoop sink(config_, "detection_sink", log_);
  std::atomic<bool> stop{true};
  try {
    (void)sink.run(stop);
    ADD_FAILURE() << "the sink resumed a journal of another run";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("written by run {corruption=clean}, but this run is "
                                         "{corruption=camera_crash/hard}"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::ifstream(config_.output).good());  // nothing written
}

// #22 item 7: a message with a wrong frame count (5 parts) is refused by the socket and counted in
// the results' meta, and the sink carries on with the next one. A respawned player or detector
// sends a sample again: the last array is kept and each repeat counted.
TEST_F(SinkLoopTest, ASecondArrayForASampleReplacesTheFirstAndIsCounted) {
  Run({Array("s1", 1), Array("s1", 2), Array("s2", 1)});
  EXPECT_EQ(counts_.duplicate_arrays, 1u);
  const auto doc = Results();
  EXPECT_EQ(doc["results"]["s1"].Size(), 2u);
  EXPECT_EQ(doc["meta"]["faultline_sink_duplicate_arrays"].GetUint64(), 1u);
  EXPECT_EQ(Lines("second DetectionArray for sample s1: it replaces the first").size(), 1u);
}

// A lockstep ack that cannot be sent (no player bound to the ack endpoint) is counted and logged
// with its cause, and the closing line says so: the player waiting for it learns nothing otherwise.
TEST_F(SinkLoopTest, AnAckThatCannotBeSentIsCountedAndLogged) {
  SinkLoop sink(config_, "detection_sink", log_);  // nothing binds config_.ack_endpoint
  transport::PublisherConfig pc;
  pc.endpoint = sink.detections_endpoint();
  pc.pattern = transport::Pattern::PushPull;
  pc.bind = false;
  pc.send_timeout_ns = 10 * kNsPerSec;
  transport::Publisher push(pc);
  std::atomic<bool> stop{false};
  auto rc = std::async(std::launch::async, [&] { return sink.run(stop); });
  ASSERT_TRUE(transport::send_message(push, "/detections", Array("s1", 1)).is_ok());
  bool logged = false;  // polled: the sink's ack send gives up after its 100 ms timeout
  for (int i = 0; i < 3000 && !logged; ++i) {
    logged = Lines("ack of sample s1 not sent").size() == 1;
    if (!logged) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  stop = true;
  ASSERT_EQ(rc.wait_for(std::chrono::seconds(30)), std::future_status::ready);
  EXPECT_EQ(rc.get(), 0);
  ASSERT_TRUE(logged);
  EXPECT_EQ(sink.counts().acks_sent, 0u);
  EXPECT_EQ(sink.counts().ack_send_failures, 1u);
  EXPECT_EQ(Lines("1 acks (1 ack send failures, 0 refused by the player)").size(), 0u);
  EXPECT_EQ(Lines("0 acks (1 ack send failures, 0 refused by the player)").size(), 1u);
}

// Samples announced by a boundary whose detections never came are written as empty and named.
TEST_F(SinkLoopTest, AnnouncedSamplesWithoutDetectionsAreCountedAndNamed) {
  transport::PublisherConfig sc;
  sc.endpoint = "ipc://" + dir_ + "/sync.sock";
  transport::Publisher sync(sc);
  config_.sync_endpoints = {sync.endpoint()};
  config_.finalize_grace_ms = 0;  // the sample's array was acked before its boundary was sent
  transport::SubscriberConfig ac;
  ac.endpoints = {config_.ack_endpoint};
  ac.pattern = transport::Pattern::PushPull;
  ac.bind = true;
  transport::RawSubscriber acks(ac);
  SinkLoop sink(config_, "detection_sink", log_);
  transport::PublisherConfig pc;
  pc.endpoint = sink.detections_endpoint();
  pc.pattern = transport::Pattern::PushPull;
  pc.bind = false;
  pc.linger_ms = 200;
  transport::Publisher push(pc);
  std::atomic<bool> stop{false};
  auto rc = std::async(std::launch::async, [&] { return sink.run(stop); });
  ASSERT_TRUE(sync.wait_for_subscribers("/sync/sample", 1, 20 * kNsPerSec).is_ok());
  ASSERT_TRUE(transport::send_message(push, "/detections", Array("s1", 1)).is_ok());
  ASSERT_TRUE(acks.receive(10 * kNsPerSec).is_ok());
  for (const char* token : {"s1", "s2"}) {
    msgs::SampleBoundary b;
    b.set_sample_token(token);
    b.set_last_in_run(std::string(token) == "s2");
    ASSERT_TRUE(transport::send_message(sync, "/sync/sample", b).is_ok());
  }
  if (rc.wait_for(std::chrono::seconds(30)) != std::future_status::ready) stop = true;  // watchdog
  EXPECT_EQ(rc.get(), 0);
  EXPECT_EQ(sink.counts().unanswered_samples, 1u);
  EXPECT_EQ(Lines("1 announced samples got no detections and are written as empty: s2").size(), 1u);
  const auto doc = Results();
  EXPECT_EQ(doc["results"]["s2"].Size(), 0u);
  EXPECT_EQ(doc["meta"]["faultline_sink_unanswered_samples"].GetUint64(), 1u);
}

// The finalize grace runs on the sink's clock, not on real time: frozen, it never expires however
// long the sockets take; once the clock passes it, the sink finalizes. Acks carry the clock's
// stamps.
TEST_F(SinkLoopTest, FinalizeGraceAndAckStampsFollowTheClock) {
  constexpr StampNs kStart = 500 * kNsPerSec, kOffset = 1'700'000'000 * kNsPerSec;
  ManualClock clock(kStart, kOffset);
  transport::PublisherConfig sc;
  sc.endpoint = "ipc://" + dir_ + "/sync.sock";
  transport::Publisher sync(sc);
  config_.sync_endpoints = {sync.endpoint()};
  config_.finalize_grace_ms = 1000;
  transport::SubscriberConfig ac;
  ac.endpoints = {config_.ack_endpoint};
  ac.pattern = transport::Pattern::PushPull;
  ac.bind = true;
  transport::RawSubscriber acks(ac);
  SinkLoop sink(config_, "detection_sink", log_, clock);
  transport::PublisherConfig pc;
  pc.endpoint = sink.detections_endpoint();
  pc.pattern = transport::Pattern::PushPull;
  pc.bind = false;
  pc.linger_ms = 200;
  transport::Publisher push(pc);
  std::atomic<bool> stop{false};
  auto rc = std::async(std::launch::async, [&] { return sink.run(stop); });
  ASSERT_TRUE(sync.wait_for_subscribers("/sync/sample", 1, 20 * kNsPerSec).is_ok());
  ASSERT_TRUE(transport::send_message(push, "/detections", Array("s1", 1)).is_ok());
  auto ack = acks.receive(10 * kNsPerSec);
  ASSERT_TRUE(ack.is_ok()) << ack.status().message();
  msgs::SampleAck a;
  ASSERT_TRUE(a.ParseFromArray(ack->header().data(), static_cast<int>(ack->header().size())));
  EXPECT_EQ(a.sample_token(), "s1");
  EXPECT_EQ(a.header().publish_mono_ns(), kStart);
  EXPECT_EQ(a.header().publish_stamp_ns(), kStart + kOffset);
  for (const char* token : {"s1", "s2"}) {
    msgs::SampleBoundary b;
    b.set_sample_token(token);
    b.set_last_in_run(std::string(token) == "s2");
    ASSERT_TRUE(transport::send_message(sync, "/sync/sample", b).is_ok());
  }
  // s2 never gets detections: the sink waits for the grace period, which only the clock ends. It
  // moves in 100 ms steps until the sink is done (each step waits at most 20 ms of real time).
  int steps = 0;
  while (rc.wait_for(std::chrono::milliseconds(20)) != std::future_status::ready && steps < 2000) {
    clock.advance_by(100 * kNsPerMs);
    ++steps;
  }
  if (steps == 2000) stop = true;  // watchdog
  EXPECT_EQ(rc.get(), 0);
  EXPECT_GE(clock.now_ns(), kStart + 1000 * kNsPerMs) << "finalized before the grace period ended";
  EXPECT_EQ(sink.counts().unanswered_samples, 1u);
  EXPECT_EQ(Lines("run complete, grace period over").size(), 1u);
  EXPECT_EQ(Results()["results"]["s2"].Size(), 0u);
}

TEST_F(SinkLoopTest, AFivePartMessageIsCountedAsMalformedInTheMeta) {
  transport::SubscriberConfig ac;
  ac.endpoints = {config_.ack_endpoint};
  ac.pattern = transport::Pattern::PushPull;
  ac.bind = true;
  transport::RawSubscriber acks(ac);
  SinkLoop sink(config_, "detection_sink", log_);
  zmq::socket_t push(transport::shared_context(), zmq::socket_type::push);
  push.set(zmq::sockopt::linger, 200);
  push.connect(sink.detections_endpoint());
  std::atomic<bool> stop{false};
  auto rc = std::async(std::launch::async, [&] { return sink.run(stop); });
  for (int i = 0; i < 5; ++i) {
    zmq::message_t part("x", 1);
    push.send(part, i < 4 ? zmq::send_flags::sndmore : zmq::send_flags::none);
  }
  const std::string body =
      Array("s1", 1).SerializeAsString();  // one socket keeps order: after the bad one
  zmq::message_t topic("/detections", 11), payload(body.data(), body.size());
  push.send(topic, zmq::send_flags::sndmore);
  push.send(payload, zmq::send_flags::none);
  const auto ack = acks.receive(10 * kNsPerSec);
  stop = true;
  ASSERT_EQ(rc.wait_for(std::chrono::seconds(30)), std::future_status::ready);
  EXPECT_EQ(rc.get(), 0);
  ASSERT_TRUE(ack.is_ok()) << ack.status().message();
  EXPECT_EQ(sink.counts().detection_arrays, 1u);
  EXPECT_EQ(sink.counts().malformed, 1u);
  const auto doc = Results();
  EXPECT_EQ(doc["meta"]["faultline_sink_malformed_messages"].GetUint64(), 1u);
  EXPECT_EQ(doc["results"]["s1"].Size(), 1u);
}

}  // namespace
}  // namespace faultline::runtime
