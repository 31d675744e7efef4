// The bag player under a manual clock: pacing sleeps exactly until each message is due at the
// chosen rate, a log-time gap over max_gap_s is skipped rather than slept, and the StreamEnd it
// owes carries the clock's stamps. No real waiting: the clock jumps.
#include "runtime/bag_player.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>
#include <unistd.h>

#include <filesystem>
#include <future>

#include "bag/writer.hpp"
#include "camera_frame.pb.h"
#include "detection.pb.h"
#include "manual_clock.hpp"  // tests/
#include "runtime/bag_layout.hpp"
#include "transport/subscriber.hpp"

namespace faultline::runtime {
namespace {

namespace fs = std::filesystem;

constexpr StampNs kStart = 2000 * kNsPerSec;
constexpr StampNs kOffset = 1'700'000'000 * kNsPerSec;
constexpr StampNs kLog0 = 1'000'000'000'000'000'000;

class BagPlayerClockTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-bagplayerclock-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // `n` messages on /a, 100 ms of log time apart (plus `gap_s` after the first half), then the
  // run's last boundary 100 ms later, announcing a StreamEnd that the bag does not hold.
  std::string WriteBag(int n, double gap_s) {
    const std::string path = (dir_ / "t.mcap").string();
    auto w = bag::Writer::open(path, bag::WriterOptions{});
    EXPECT_TRUE(w.is_ok());
    const auto a =
        (*w)->add_channel("/a", 0, {{kMetaTopic, "/a"}, {kMetaFrames, "2"}}, kBodyEncoding);
    const auto sync = (*w)->add_channel(
        "/sync/sample", 0, {{kMetaTopic, "/sync/sample"}, {kMetaFrames, "2"}}, kBodyEncoding);
    StampNs t = kLog0;
    for (int i = 0; i < n; ++i) {
      if (i == n / 2) t += static_cast<StampNs>(gap_s * kNsPerSec);
      msgs::SampleAck body;
      body.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
      EXPECT_TRUE(
          (*w)->write(a.value(), static_cast<std::uint64_t>(i + 1), t, t, body.SerializeAsString())
              .is_ok());
      t += 100 * kNsPerMs;
    }
    msgs::SampleBoundary b;
    b.set_sample_token("s1");
    b.set_last_in_run(true);
    b.set_stream_end_follows(true);
    EXPECT_TRUE((*w)->write(sync.value(), 1, t, t, b.SerializeAsString()).is_ok());
    EXPECT_TRUE((*w)->close().is_ok());
    return path;
  }

  // Plays `file` with a manual clock; returns the StreamEnd's header once it arrived.
  msgs::Header Play(const std::string& file, double rate, double max_gap_s) {
    BagPlayerConfig pc;
    pc.files = {file};
    pc.rate = rate;
    pc.max_gap_s = max_gap_s;
    pc.endpoint = "ipc://" + (dir_ / "play.sock").string();
    pc.wait_subscribers = 1;
    BagPlayer player(pc,
                     std::make_shared<spdlog::logger>(
                         "bag_player_test", std::make_shared<spdlog::sinks::null_sink_mt>()),
                     clock_);
    transport::SubscriberConfig sc;
    sc.endpoints = {player.endpoint()};
    sc.topics = {""};
    sc.rcv_hwm = 1000;
    transport::RawSubscriber sub(sc);
    std::atomic<bool> stop{false};
    auto rc = std::async(std::launch::async, [&] { return player.run(stop); });
    msgs::Header end;
    for (;;) {
      auto r = sub.receive(10 * kNsPerSec);
      if (!r.is_ok()) {
        ADD_FAILURE() << "no StreamEnd: " << r.status().message();
        break;
      }
      if (r->topic() != "/sync/end") continue;
      msgs::StreamEnd e;
      EXPECT_TRUE(e.ParseFromArray(r->header().data(), static_cast<int>(r->header().size())));
      end = e.header();
      break;
    }
    EXPECT_EQ(rc.get(), 0);
    return end;
  }

  // The sleeps of a paced run: due times `step` apart from kStart, for messages first..last.
  static std::vector<StampNs> Due(int first, int last, StampNs base, DurationNs step) {
    std::vector<StampNs> out;
    for (int i = first; i <= last; ++i) out.push_back(base + i * step);
    return out;
  }

  fs::path dir_;
  ManualClock clock_{kStart, kOffset};
};

TEST_F(BagPlayerClockTest, SleepsUntilEachMessageIsDueAtTheRate) {
  const auto end = Play(WriteBag(10, 0), /*rate=*/2.0, /*max_gap_s=*/10);
  // 100 ms of log time is 50 ms at rate 2: messages 1..10 (the boundary last) each sleep once.
  EXPECT_EQ(clock_.sleeps(), Due(1, 10, kStart, 50 * kNsPerMs));
  EXPECT_EQ(end.publish_mono_ns(), kStart + 500 * kNsPerMs);
  EXPECT_EQ(end.publish_stamp_ns(), kStart + 500 * kNsPerMs + kOffset);
}

TEST_F(BagPlayerClockTest, GapOverMaxGapIsSkippedNotSlept) {
  Play(WriteBag(10, /*gap_s=*/20), /*rate=*/2.0, /*max_gap_s=*/10);
  // Messages 1-4 are paced from message 0; message 5 comes after the gap and is sent at once,
  // re-anchoring the pacing; 6-9 and the boundary follow 50 ms apart.
  auto expected = Due(1, 4, kStart, 50 * kNsPerMs);
  for (StampNs t : Due(1, 5, kStart + 200 * kNsPerMs, 50 * kNsPerMs)) expected.push_back(t);
  EXPECT_EQ(clock_.sleeps(), expected);
  EXPECT_EQ(clock_.now_ns(), kStart + 450 * kNsPerMs);
}

TEST_F(BagPlayerClockTest, GapIsSleptThroughTheClockWhenNeverSkipped) {
  const auto end = Play(WriteBag(10, /*gap_s=*/20), /*rate=*/2.0, /*max_gap_s=*/0);
  // 20 s of gap at rate 2 is 10 s of clock time, slept in 50 ms slices (no real waiting).
  const StampNs last = kStart + 500 * kNsPerMs + 10 * kNsPerSec;
  EXPECT_EQ(clock_.now_ns(), last);
  // Messages 1-4 one sleep each, message 5 10.05 s in 201 slices, 6-9 and the boundary one each.
  EXPECT_EQ(clock_.sleeps().size(), 4u + 201u + 5u);
  EXPECT_EQ(end.publish_mono_ns(), last);
}

}  // namespace
}  // namespace faultline::runtime
