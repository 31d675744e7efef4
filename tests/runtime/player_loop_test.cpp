// One run of the player under a manual clock: real-time pacing sleeps exactly until each frame is
// due, a scene change re-anchors instead of sleeping the days between scenes, and every message's
// publish stamps are the clock's readings at that moment. No real waiting: the clock jumps.
#include "runtime/player_loop.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <future>
#include <opencv2/imgcodecs.hpp>

#include "common/logging.hpp"
#include "detection.pb.h"
#include "manual_clock.hpp"  // tests/
#include "stats.pb.h"
#include "transport/subscriber.hpp"

namespace faultline::runtime {
namespace {

constexpr StampNs kStart = 1000 * kNsPerSec;
constexpr StampNs kRealtimeOffset = 1'700'000'000 * kNsPerSec;
constexpr std::int64_t kT0us = 1'600'000'000'000'000;
constexpr std::int64_t kDayUs = 86'400'000'000;

struct Received {
  std::string topic;
  StampNs mono_ns = 0;
  StampNs realtime_ns = 0;
};

class PlayerLoopClockTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-playerclock-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    ::setenv("FAULTLINE_RUN_DIR", (dir_ + "/graph").c_str(), 1);
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }

  void AddFrame(const std::string& scene, const std::string& sample, std::int64_t t_us, bool key) {
    dataset::CameraFrameRecord f;
    f.channel = "CAM_FRONT";
    f.filename = "img" + std::to_string(frames_.size()) + ".jpg";
    f.sample_data_token = "sd-" + f.filename;
    f.sample_token = sample;
    f.scene_token = scene;
    f.scene_name = scene;
    f.is_key_frame = key;
    f.timestamp_us = t_us;
    f.width = 8;
    f.height = 8;
    cv::Mat img(8, 8, CV_8UC3, cv::Scalar(10, 20, 30));
    std::vector<std::uint8_t> bytes;
    cv::imencode(".jpg", img, bytes);
    images_[f.filename] = std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes));
    frames_.push_back(f);
  }

  // Plays every frame at `rate` and returns what a subscriber received, up to the statistics that
  // follow the StreamEnd.
  std::vector<Received> Play(double rate) {
    PlayerConfig pc;
    pc.rate = rate;
    pc.endpoint = "ipc://" + dir_ + "/player.sock";
    pc.hwm = 64;
    pc.wait_subscribers = 1;
    PlayerLoop player(pc, "nusc_player", std::make_unique<MemoryFrameSource>(frames_, images_),
                      clock_, logging::make_node_logger("player_loop_test", "warn"));
    transport::SubscriberConfig sc;
    sc.endpoints = {player.endpoint()};
    sc.topics = {""};
    sc.rcv_hwm = 1000;
    transport::RawSubscriber sub(sc);
    std::atomic<bool> stop{false};
    auto rc = std::async(std::launch::async, [&] { return player.run(stop); });
    std::vector<Received> got;
    for (;;) {
      auto r = sub.receive(10 * kNsPerSec);
      if (!r.is_ok()) break;
      msgs::StreamEnd any;  // every message starts with its Header (field 1)
      EXPECT_TRUE(any.ParseFromArray(r->header().data(), static_cast<int>(r->header().size())));
      got.push_back({std::string(r->topic()), any.header().publish_mono_ns(),
                     any.header().publish_stamp_ns()});
      if (got.back().topic == "/statistics" && got.size() > 1 &&
          got[got.size() - 2].topic == "/sync/end")
        break;
    }
    EXPECT_EQ(rc.get(), 0);
    counts_ = player.counts();
    return got;
  }

  std::string dir_;
  ManualClock clock_{kStart, kRealtimeOffset};
  std::vector<dataset::CameraFrameRecord> frames_;
  std::map<std::string, ImageBytes> images_;
  PlayerCounts counts_;
};

TEST_F(PlayerLoopClockTest, PacesByTheClockAndStampsWithIt) {
  AddFrame("scene-a", "s1", kT0us, false);
  AddFrame("scene-a", "s1", kT0us + 50'000, false);
  AddFrame("scene-a", "s1", kT0us + 100'000, true);
  AddFrame("scene-b", "s2", kT0us + kDayUs, true);  // a day later: re-anchored, not slept
  const auto got = Play(/*rate=*/2.0);

  // Twice real time: 50 ms of dataset time is 25 ms of clock time; nothing else slept.
  EXPECT_EQ(clock_.sleeps(),
            (std::vector<StampNs>{kStart + 25 * kNsPerMs, kStart + 50 * kNsPerMs}));
  const StampNs last = kStart + 50 * kNsPerMs;
  std::vector<std::pair<std::string, StampNs>> expected = {
      {"/cam_front/image_rect_compressed", kStart},
      {"/cam_front/image_rect_compressed", kStart + 25 * kNsPerMs},
      {"/cam_front/image_rect_compressed", last},
      {"/sync/sample", last},
      {"/cam_front/image_rect_compressed", last},  // the new scene starts at once
      {"/sync/sample", last}};
  std::vector<std::pair<std::string, StampNs>> frames_and_boundaries;
  for (const auto& r : got) {
    EXPECT_EQ(r.realtime_ns, r.mono_ns + kRealtimeOffset) << r.topic;
    if (r.topic == "/statistics" || r.topic == "/sync/end") {
      EXPECT_EQ(r.mono_ns, last) << r.topic;  // the end of the run
      continue;
    }
    frames_and_boundaries.emplace_back(r.topic, r.mono_ns);
  }
  EXPECT_EQ(frames_and_boundaries, expected);
  ASSERT_GE(got.size(), 2u);
  // The end of the run: the StreamEnd, then the last statistics window (its start and end on the
  // clock too), one TopicStats for the camera topic.
  EXPECT_EQ(got[got.size() - 2].topic, "/sync/end");
  EXPECT_EQ(got.back().topic, "/statistics");
  EXPECT_EQ(got.size(), expected.size() + 2);
  EXPECT_EQ(counts_.frames_sent, 4u);
  EXPECT_EQ(counts_.boundaries_sent, 2u);
}

TEST_F(PlayerLoopClockTest, UnpacedRunNeverSleeps) {
  AddFrame("scene-a", "s1", kT0us, false);
  AddFrame("scene-a", "s1", kT0us + 10 * kDayUs, true);
  const auto got = Play(/*rate=*/0.0);
  EXPECT_TRUE(clock_.sleeps().empty());
  EXPECT_EQ(clock_.now_ns(), kStart);
  for (const auto& r : got) EXPECT_EQ(r.mono_ns, kStart) << r.topic;
  EXPECT_EQ(counts_.frames_sent, 2u);
}

}  // namespace
}  // namespace faultline::runtime
