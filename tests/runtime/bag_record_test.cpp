// Recorder/player over the live transport: a publisher thread over ipc, BagRecorder in a thread
// with a stop flag, then the bag read back and played into a RawSubscriber.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "bag/reader.hpp"
#include "bag/writer.hpp"
#include "camera_frame.pb.h"
#include "detection.pb.h"
#include "runtime/bag_layout.hpp"
#include "runtime/bag_player.hpp"
#include "runtime/bag_recorder.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {
namespace {

namespace fs = std::filesystem;
constexpr const char* kImageTopic = "/cam_front/image_rect_compressed";
constexpr const char* kSyncTopic = "/sync/sample";

struct SentMessage {
  std::string topic, header, payload;  // payload empty for two-part messages
  std::uint64_t seq = 0;
};

std::shared_ptr<spdlog::logger> quiet_logger() {
  return std::make_shared<spdlog::logger>("bag_record_test",
                                          std::make_shared<spdlog::sinks::null_sink_mt>());
}

// Spins (yielding) until pred() holds or 20 s pass; the bound only turns a hang into a failure.
template <class Pred>
bool wait_for(Pred pred) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!pred()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::yield();
  }
  return true;
}

class BagRecordTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("faultline_bag_record_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    endpoint_ = "ipc://" + (dir_ / "pub.sock").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Frames with seq 1..n except `skip` (a transport gap), a SampleBoundary after every 4th frame.
  std::vector<SentMessage> make_stream(int n, std::uint64_t skip) {
    std::vector<SentMessage> out;
    std::uint64_t sync_seq = 0;
    for (int i = 1; i <= n; ++i) {
      const auto seq = static_cast<std::uint64_t>(i);
      if (seq != skip) {
        msgs::CameraFrame f;
        f.mutable_header()->set_seq(seq);
        f.mutable_header()->set_publish_stamp_ns(1'700'000'000'000'000'000 + i * 83'000'000LL);
        f.mutable_header()->set_capture_stamp_ns(1'700'000'000'000'000'000 + i * 83'000'000LL);
        f.mutable_header()->set_publisher("test_pub");
        f.set_camera("CAM_FRONT");
        f.set_encoding("jpeg");
        f.set_width(16);
        f.set_height(8);
        for (int k = 0; k < 9; ++k) f.add_intrinsics(k == 0 || k == 4 ? 100.0 : k == 8 ? 1.0 : 0.0);
        f.mutable_ego_pose()->mutable_rotation()->set_w(1.0);
        std::string payload(1000 + 37 * i, '\0');
        for (std::size_t b = 0; b < payload.size(); ++b)
          payload[b] = static_cast<char>((b * 31 + i) & 0xff);
        f.set_payload_bytes(static_cast<std::uint32_t>(payload.size()));
        out.push_back({kImageTopic, f.SerializeAsString(), payload, seq});
      }
      if (i % 4 == 0) {
        msgs::SampleBoundary b;
        b.mutable_header()->set_seq(++sync_seq);
        b.mutable_header()->set_publisher("test_pub");
        b.mutable_header()->set_publish_stamp_ns(1'700'000'000'000'000'000 + i * 83'000'000LL);
        b.set_sample_token("sample" + std::to_string(i / 4));
        out.push_back({kSyncTopic, b.SerializeAsString(), "", sync_seq});
      }
    }
    return out;
  }

  static void send_all(transport::Publisher& pub, const std::vector<SentMessage>& stream) {
    for (const auto& m : stream) {
      Status s;
      if (m.payload.empty()) {
        s = pub.send(m.topic, m.header);
      } else {
        transport::Payload p;
        p.data = reinterpret_cast<const std::uint8_t*>(m.payload.data());
        p.size_bytes = m.payload.size();
        s = pub.send(m.topic, m.header, p);
      }
      ASSERT_TRUE(s.is_ok()) << s.to_string();
    }
  }

  RecorderConfig recorder_config() const {
    RecorderConfig cfg;
    cfg.output = (dir_ / "run.mcap").string();
    cfg.topics = {kImageTopic, kSyncTopic};
    cfg.endpoints = {endpoint_};
    cfg.run_metadata["seed"] = "42";
    return cfg;
  }

  transport::PublisherConfig publisher_config() const {
    transport::PublisherConfig pc;
    pc.endpoint = endpoint_;
    pc.snd_hwm = 1000;
    pc.zero_copy = false;
    return pc;
  }

  // Records `stream` completely and returns the recorder's exit code.
  int record(const std::vector<SentMessage>& stream, BagRecorder& recorder) {
    transport::Publisher pub(publisher_config());
    std::atomic<bool> stop{false};
    int rc = -1;
    std::thread t([&] { rc = recorder.run(stop); });
    EXPECT_TRUE(pub.wait_for_subscribers(kImageTopic, 1, 10 * kNsPerSec).is_ok());
    EXPECT_TRUE(pub.wait_for_subscribers(kSyncTopic, 1, 10 * kNsPerSec).is_ok());
    send_all(pub, stream);
    EXPECT_TRUE(wait_for([&] { return recorder.recorded() >= stream.size(); }));
    stop = true;
    t.join();
    return rc;
  }

  fs::path dir_;
  std::string endpoint_;
};

struct ReadBack {
  std::vector<SentMessage> replay;  // from the replay channels, in file order
  std::map<std::string, std::string> schema_of_topic;
  std::map<std::string, std::size_t> count_of_topic;
};

ReadBack read_back(const std::string& path) {
  ReadBack out;
  auto reader = bag::Reader::open(path);
  EXPECT_TRUE(reader.is_ok());
  if (!reader) return out;
  auto scan = (*reader)->read_linear({}, [&](const bag::MessageView& v) {
    out.schema_of_topic[v.channel->topic] = v.schema ? v.schema->name : "";
    ++out.count_of_topic[v.channel->topic];
    const auto frames = v.channel->metadata.find(kMetaFrames);
    if (frames == v.channel->metadata.end()) return true;
    SentMessage m;
    m.topic = v.channel->metadata.at(kMetaTopic);
    m.seq = v.sequence;
    if (frames->second == "3") {
      auto mp = decode_multipart(v.data);
      EXPECT_TRUE(mp.is_ok());
      if (!mp) return true;
      m.header = std::string(mp->header);
      m.payload = std::string(mp->payload);
    } else {
      m.header = std::string(v.data);
    }
    out.replay.push_back(std::move(m));
    return true;
  });
  EXPECT_TRUE(scan.is_ok());
  if (scan) {
    EXPECT_TRUE(scan->footer_found);
    EXPECT_EQ(scan->problems, 0u);
  }
  return out;
}

void expect_same(const std::vector<SentMessage>& a, const std::vector<SentMessage>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].topic, b[i].topic) << "message " << i;
    EXPECT_EQ(a[i].header, b[i].header) << "message " << i;
    EXPECT_EQ(a[i].payload, b[i].payload) << "message " << i;
    EXPECT_EQ(a[i].seq, b[i].seq) << "message " << i;
  }
}

TEST(BagLayoutTest, MultipartRoundTripsAndRejectsBadLength) {
  const std::string data = encode_multipart("hdr", std::string("\0pay", 4));
  auto mp = decode_multipart(data);
  ASSERT_TRUE(mp.is_ok());
  EXPECT_EQ(mp->header, "hdr");
  EXPECT_EQ(mp->payload, std::string_view("\0pay", 4));
  EXPECT_FALSE(decode_multipart(data.substr(0, 5)).is_ok());
  EXPECT_FALSE(decode_multipart("ab").is_ok());
}

TEST(BagLayoutTest, ReadsHeaderOfAnyMessage) {
  msgs::SampleAck ack;
  ack.set_sample_token("tok");
  ack.mutable_header()->set_seq(77);
  ack.mutable_header()->set_publish_stamp_ns(123);
  ack.mutable_header()->set_publisher("sink");
  HeaderFields h;
  ASSERT_TRUE(read_header_fields(ack.SerializeAsString(), &h));
  EXPECT_EQ(h.seq, 77u);
  EXPECT_EQ(h.publish_stamp_ns, 123);
  EXPECT_EQ(h.publisher, "sink");
  EXPECT_FALSE(read_header_fields("\xff\xff", &h));
  EXPECT_EQ(sibling_camera_info_topic("/faulty/cam_front/image_rect_compressed"),
            "/faulty/cam_front/camera_info");
}

TEST_F(BagRecordTest, RecordsLiveStreamByteExactWithDrops) {
  const auto stream = make_stream(24, 5);
  BagRecorder recorder(recorder_config(), quiet_logger());
  ASSERT_EQ(record(stream, recorder), 0);
  ASSERT_EQ(recorder.paths().size(), 1u);
  const ReadBack rb = read_back(recorder.paths()[0]);
  expect_same(stream, rb.replay);
  EXPECT_EQ(recorder.drops().topic_counts(kImageTopic).transport_drops, 1u);
  EXPECT_EQ(recorder.drops().topic_counts(kSyncTopic).transport_drops, 0u);
  // Foxglove view beside the replay channels.
  EXPECT_EQ(rb.schema_of_topic.at(kImageTopic), "foxglove.CompressedImage");
  EXPECT_EQ(rb.count_of_topic.at(kImageTopic), 23u);
  EXPECT_EQ(rb.schema_of_topic.at("/cam_front/camera_info"), "foxglove.CameraCalibration");
  EXPECT_EQ(rb.schema_of_topic.at("/tf"), "foxglove.FrameTransform");
  EXPECT_EQ(rb.schema_of_topic.at(kSyncTopic), "faultline.msgs.SampleBoundary");
  // Metadata: run configuration and drop counts.
  auto reader = bag::Reader::open(recorder.paths()[0]);
  ASSERT_TRUE(reader.is_ok());
  auto meta = (*reader)->read_metadata();
  ASSERT_TRUE(meta.is_ok());
  std::map<std::string, bag::KeyValueMap> by_name;
  for (const auto& m : *meta) by_name[m.name] = m.metadata;
  ASSERT_EQ(by_name.count("faultline.run"), 1u);
  EXPECT_EQ(by_name["faultline.run"]["seed"], "42");
  EXPECT_FALSE(by_name["faultline.run"]["version"].empty());
  ASSERT_EQ(by_name.count("faultline.drops"), 1u);
  EXPECT_EQ(by_name["faultline.drops"][std::string(kImageTopic) + "@test_pub"],
            "received=23 transport_drops=1 restarts=0");
}

TEST_F(BagRecordTest, PlayRepublishesRecordingExactly) {
  const auto stream = make_stream(16, 0);
  BagRecorder recorder(recorder_config(), quiet_logger());
  ASSERT_EQ(record(stream, recorder), 0);
  const ReadBack rb = read_back(recorder.paths()[0]);

  BagPlayerConfig pc;
  pc.files = recorder.paths();
  pc.rate = 0;
  pc.endpoint = "ipc://" + (dir_ / "play.sock").string();
  pc.wait_subscribers = 1;
  BagPlayer player(pc, quiet_logger());
  transport::SubscriberConfig sc;
  sc.endpoints = {player.endpoint()};
  sc.topics = {""};
  sc.rcv_hwm = 1000;
  transport::RawSubscriber sub(sc);
  std::atomic<bool> stop{false};
  int rc = -1;
  std::thread t([&] { rc = player.run(stop); });
  std::vector<SentMessage> got;
  while (got.size() < rb.replay.size()) {
    auto r = sub.receive(10 * kNsPerSec);
    ASSERT_TRUE(r.is_ok()) << "after " << got.size() << " messages: " << r.status().to_string();
    SentMessage m;
    m.topic = std::string(r->topic());
    m.header = std::string(r->header());
    if (r->has_payload())
      m.payload.assign(reinterpret_cast<const char*>(r->payload_data()), r->payload_size());
    HeaderFields h;
    ASSERT_TRUE(read_header_fields(m.header, &h));
    m.seq = h.seq;
    got.push_back(std::move(m));
  }
  t.join();
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(player.counts().messages_sent, rb.replay.size());
  expect_same(rb.replay, got);
  expect_same(stream, got);
}

TEST_F(BagRecordTest, LockstepPlayWaitsForEachSampleAck) {
  const auto stream = make_stream(12, 0);
  BagRecorder recorder(recorder_config(), quiet_logger());
  ASSERT_EQ(record(stream, recorder), 0);

  BagPlayerConfig pc;
  pc.files = recorder.paths();
  pc.rate = 0;
  pc.endpoint = "ipc://" + (dir_ / "play.sock").string();
  pc.ack_endpoint = "ipc://" + (dir_ / "ack.sock").string();
  pc.lockstep = true;
  pc.ack_timeout_ms =
      0;  // wait forever: a missing ack would hang, caught by the receive timeout below
  pc.wait_subscribers = 1;
  BagPlayer player(pc, quiet_logger());
  transport::SubscriberConfig sc;
  sc.endpoints = {player.endpoint()};
  sc.topics = {""};
  sc.rcv_hwm = 1000;
  transport::RawSubscriber sub(sc);
  transport::PublisherConfig ac;
  ac.endpoint = player.ack_endpoint();
  ac.pattern = transport::Pattern::PushPull;
  ac.bind = false;
  ac.linger_ms = 200;
  transport::Publisher acks(ac);
  std::atomic<bool> stop{false};
  int rc = -1;
  std::thread t([&] { rc = player.run(stop); });
  std::vector<SentMessage> got;
  std::size_t acked = 0;
  while (got.size() < stream.size()) {
    auto r = sub.receive(10 * kNsPerSec);
    ASSERT_TRUE(r.is_ok()) << "after " << got.size() << " messages: " << r.status().to_string();
    SentMessage m;
    m.topic = std::string(r->topic());
    m.header = std::string(r->header());
    if (r->has_payload())
      m.payload.assign(reinterpret_cast<const char*>(r->payload_data()), r->payload_size());
    HeaderFields h;
    ASSERT_TRUE(read_header_fields(m.header, &h));
    m.seq = h.seq;
    if (m.topic == kSyncTopic) {
      msgs::SampleBoundary b;
      ASSERT_TRUE(b.ParseFromString(m.header));
      msgs::SampleAck ack;
      ack.set_sample_token(b.sample_token());
      ASSERT_TRUE(transport::send_message(acks, "/sync/ack", ack).is_ok());
      ++acked;
    }
    got.push_back(std::move(m));
  }
  t.join();
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(acked, 3u);
  EXPECT_EQ(player.counts().ack_timeouts, 0u);
  expect_same(stream, got);
}

TEST_F(BagRecordTest, StopDuringRecordingLeavesIndexedFile) {
  RecorderConfig cfg = recorder_config();
  BagRecorder recorder(cfg, quiet_logger());
  transport::Publisher pub(publisher_config());
  std::atomic<bool> stop{false}, done{false};
  int rc = -1;
  std::thread rec([&] { rc = recorder.run(stop); });
  ASSERT_TRUE(pub.wait_for_subscribers(kImageTopic, 1, 10 * kNsPerSec).is_ok());
  // Publisher keeps sending while the stop arrives, as with SIGINT in a live run.
  std::thread sender([&] {
    const auto stream = make_stream(400, 0);
    for (const auto& m : stream) {
      if (done.load()) break;
      transport::Payload p;
      p.data = reinterpret_cast<const std::uint8_t*>(m.payload.data());
      p.size_bytes = m.payload.size();
      (void)(m.payload.empty() ? pub.send(m.topic, m.header) : pub.send(m.topic, m.header, p));
    }
  });
  ASSERT_TRUE(wait_for([&] { return recorder.recorded() >= 10; }));
  stop = true;
  rec.join();
  done = true;
  sender.join();
  EXPECT_EQ(rc, 0);
  auto reader = bag::Reader::open(cfg.output);
  ASSERT_TRUE(reader.is_ok());
  ASSERT_TRUE((*reader)->load_summary().is_ok());
  ASSERT_TRUE((*reader)->summary().statistics.has_value());
  std::uint64_t replayed = 0;
  ASSERT_TRUE((*reader)
                  ->read_indexed({},
                                 [&](const bag::MessageView& v) {
                                   replayed += v.channel->metadata.count(kMetaFrames);
                                   return true;
                                 })
                  .is_ok());
  EXPECT_EQ(replayed, recorder.counts().messages);
  EXPECT_GE(replayed, 10u);
  // Independent check with @mcap/core when the Node validator is installed.
  const fs::path js = fs::path(FAULTLINE_SOURCE_DIR) / "tests/mcap_js";
  if (fs::exists(js / "node_modules/@mcap/core") &&
      std::system("node --version > /dev/null 2>&1") == 0) {
    const std::string cmd =
        "node " + (js / "validate_mcap.mjs").string() + " " + cfg.output + " > /dev/null";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
}

// A replay bag written directly with controlled log times: two-part messages on /a and /b
// alternating, message i at 1e18 + i * 100 ms (+ gap_s after the first half), seq per topic.
std::string write_timed_bag(const fs::path& path, int n, double gap_s = 0) {
  auto w = bag::Writer::open(path.string(), bag::WriterOptions{});
  EXPECT_TRUE(w.is_ok());
  std::map<std::string, std::uint16_t> ch;
  std::map<std::string, std::uint64_t> seq;
  for (const char* t : {"/a", "/b"}) {
    ch[t] = (*w)->add_channel(t, 0, {{kMetaTopic, t}, {kMetaFrames, "2"}}, kBodyEncoding).value();
  }
  for (int i = 0; i < n; ++i) {
    const std::string topic = i % 2 == 0 ? "/a" : "/b";
    msgs::SampleAck body;  // any message with a Header
    body.mutable_header()->set_seq(++seq[topic]);
    body.set_sample_token("m" + std::to_string(i));
    StampNs t = 1'000'000'000'000'000'000 + i * 100 * kNsPerMs;
    if (i >= n / 2) t += static_cast<StampNs>(gap_s * kNsPerSec);
    EXPECT_TRUE((*w)->write(ch[topic], seq[topic], t, t, body.SerializeAsString()).is_ok());
  }
  EXPECT_TRUE((*w)->close().is_ok());
  return path.string();
}

struct Played {
  std::string topic, token;
};

class BagPlayOptionsTest : public BagRecordTest {
 protected:
  BagPlayerConfig config(const std::string& file) const {
    BagPlayerConfig pc;
    pc.files = {file};
    pc.rate = 0;
    pc.endpoint = "ipc://" + (dir_ / "play.sock").string();
    pc.wait_subscribers = 1;
    return pc;
  }
  // Plays with `pc` into a subscriber until `expect` messages arrived (or 10 s of silence), then
  // stops the player; `during` runs after the subscriber connected.
  std::vector<Played> play(
      BagPlayerConfig pc, std::size_t expect, double* wall_s = nullptr,
      const std::function<void(BagPlayer&, transport::RawSubscriber&)>& during = {},
      const BagPlayProgressFn& progress = {}) {
    BagPlayer player(pc, quiet_logger());
    transport::SubscriberConfig sc;
    sc.endpoints = {player.endpoint()};
    sc.topics = {""};
    sc.rcv_hwm = 1000;
    transport::RawSubscriber sub(sc);
    std::atomic<bool> stop{false};
    int rc = -1;
    const auto t0 = std::chrono::steady_clock::now();
    std::thread t([&] { rc = player.run(stop, progress); });
    if (during) during(player, sub);
    std::vector<Played> got;
    // Up to `expect` messages; a player that ends by itself (no loop) is then joined and whatever
    // else it sent is collected too, so extra messages are seen.
    while (got.size() < expect || !pc.loop) {
      auto r = sub.receive(got.size() < expect ? 10 * kNsPerSec : 200 * kNsPerMs);
      if (!r) break;
      msgs::SampleAck a;
      EXPECT_TRUE(a.ParseFromArray(r->header().data(), static_cast<int>(r->header().size())));
      got.push_back({std::string(r->topic()), a.sample_token()});
    }
    if (pc.loop) stop = true;
    t.join();
    if (wall_s)
      *wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(rc, 0);
    return got;
  }
};

std::vector<std::string> tokens(const std::vector<Played>& p) {
  std::vector<std::string> out;
  for (const auto& x : p) out.push_back(x.token);
  return out;
}

std::vector<std::string> range_tokens(int from, int to) {  // m<from> .. m<to-1>
  std::vector<std::string> out;
  for (int i = from; i < to; ++i) out.push_back("m" + std::to_string(i));
  return out;
}

TEST_F(BagPlayOptionsTest, StartOffsetAndDurationSelectTheBagTimeWindow) {
  auto pc = config(write_timed_bag(dir_ / "t.mcap", 40));
  pc.start_offset_s = 0.5;  // from message 5 (0.5 s)
  pc.duration_s = 1.0;      // through message 15 (1.5 s)
  EXPECT_EQ(tokens(play(pc, 11)), range_tokens(5, 16));
}

TEST_F(BagPlayOptionsTest, IncludeExcludeAndRemapWorkOnTransportTopics) {
  auto pc = config(write_timed_bag(dir_ / "t.mcap", 10));
  pc.include = {"^/a$"};
  auto a = play(pc, 5);
  ASSERT_EQ(a.size(), 5u);
  for (const auto& p : a) EXPECT_EQ(p.topic, "/a");
  pc.include.clear();
  pc.exclude = {"^/a$"};
  pc.remap = {{"/b", "/renamed/b"}};
  auto b = play(pc, 5);
  ASSERT_EQ(b.size(), 5u);
  for (const auto& p : b) EXPECT_EQ(p.topic, "/renamed/b");
  EXPECT_EQ(b.front().token, "m1");
}

TEST_F(BagPlayOptionsTest, LoopRepeatsTheBagUntilStopped) {
  auto pc = config(write_timed_bag(dir_ / "t.mcap", 6));
  pc.loop = true;
  auto got = play(pc, 18);
  auto expected = range_tokens(0, 6);
  for (int k = 0; k < 2; ++k) {
    const auto once = range_tokens(0, 6);
    expected.insert(expected.end(), once.begin(), once.end());
  }
  EXPECT_EQ(tokens(got), expected);
}

TEST_F(BagPlayOptionsTest, RatePacesByLogTimeAndLongGapsAreSkipped) {
  // 20 messages over 1.9 s of bag time at rate 4: at least 0.475 s of wall time.
  auto pc = config(write_timed_bag(dir_ / "t.mcap", 20));
  pc.rate = 4;
  double wall = 0;
  EXPECT_EQ(play(pc, 20, &wall).size(), 20u);
  EXPECT_GE(wall, 1.9 / 4);
  // A one-hour gap in the middle is skipped (max_gap_s), not slept.
  auto gap = config(write_timed_bag(dir_ / "gap.mcap", 20, 3600));
  gap.rate = 20;
  EXPECT_EQ(play(gap, 20, &wall).size(), 20u);
  EXPECT_LT(wall, 60.0);
}

TEST_F(BagPlayOptionsTest, StartPausedStepsAndResumesFromTheControlSocket) {
  auto pc = config(write_timed_bag(dir_ / "t.mcap", 12));
  pc.start_paused = true;
  pc.control_endpoint = "ipc://" + (dir_ / "ctl.sock").string();
  auto got = play(pc, 10, nullptr, [&](BagPlayer& player, transport::RawSubscriber& sub) {
    EXPECT_TRUE(player.paused());
    EXPECT_EQ(sub.receive(300 * kNsPerMs).status().code(), StatusCode::kWouldBlock)
        << "paused: nothing sent";
    transport::PublisherConfig cc;
    cc.endpoint = player.control_endpoint();
    cc.pattern = transport::Pattern::PushPull;
    cc.bind = false;
    cc.linger_ms = 200;
    transport::Publisher ctl(cc);
    ASSERT_TRUE(ctl.send("/ctl", "step 2").is_ok());
    ASSERT_TRUE(wait_for([&] { return player.sent() == 2; }));
    EXPECT_EQ(sub.receive(300 * kNsPerMs).is_ok(), true);  // the two stepped messages are queued
    EXPECT_EQ(sub.receive(300 * kNsPerMs).is_ok(), true);
    EXPECT_EQ(sub.receive(300 * kNsPerMs).status().code(), StatusCode::kWouldBlock)
        << "a step sends exactly N";
    EXPECT_TRUE(player.paused());
    ASSERT_TRUE(ctl.send("/ctl", "bogus").is_ok());  // logged and ignored
    ASSERT_TRUE(ctl.send("/ctl", "resume").is_ok());
  });
  EXPECT_EQ(got.size(), 10u);  // the rest after resume
  EXPECT_EQ(tokens(got), range_tokens(2, 12));
}

TEST_F(BagPlayOptionsTest, ProgressReportsBagTimeOverDuration) {
  auto pc = config(write_timed_bag(dir_ / "t.mcap", 10));
  std::vector<BagPlayProgress> reports;
  EXPECT_EQ(
      play(pc, 10, nullptr, {}, [&](const BagPlayProgress& p) { reports.push_back(p); }).size(),
      10u);
  ASSERT_GE(reports.size(), 2u);  // the first message, then the end of the run
  EXPECT_EQ(reports.front().messages_sent, 1u);
  const BagPlayProgress& last = reports.back();
  EXPECT_TRUE(last.finished);
  EXPECT_EQ(last.messages_sent, 10u);
  EXPECT_DOUBLE_EQ(last.total_seconds, 0.9);
  EXPECT_EQ(format_progress(last), "[play] bag time     0.90 / 0.90 s  messages 10            ");
  BagPlayProgress paused = last;
  paused.paused = true;
  EXPECT_EQ(format_progress(paused), "[play] bag time     0.90 / 0.90 s  messages 10  [paused]  ");
}

}  // namespace
}  // namespace faultline::runtime
