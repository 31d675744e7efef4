#include "stats/topic_stats.hpp"

#include <gtest/gtest.h>

namespace faultline::stats {
namespace {

constexpr StampNs kStart = 1'000 * kNsPerSec;

Sample At(StampNs mono, DurationNs latency_ns, std::uint64_t size) {
  Sample s;
  s.receive_mono_ns = mono;
  s.publish_mono_ns = mono - latency_ns;
  s.receive_realtime_ns = mono + 5 * kNsPerSec;
  s.capture_stamp_ns = mono + 5 * kNsPerSec - 20 * kNsPerMs;  // 20 ms old
  s.size_bytes = size;
  return s;
}

TEST(TopicStatsTest, WindowSummarisesPeriodLatencyAgeAndSize) {
  TopicStatsCollector c(kNsPerSec, kStart);
  for (int i = 0; i < 12; ++i) {
    c.record("/cam_front/x", "player", At(kStart + i * 83 * kNsPerMs, 2 * kNsPerMs, 1000));
  }
  ASSERT_FALSE(c.window_elapsed(kStart + 999 * kNsPerMs));
  ASSERT_TRUE(c.window_elapsed(kStart + kNsPerSec));
  const auto w = c.take_window(kStart + kNsPerSec);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].received, 12u);
  EXPECT_EQ(w[0].publisher, "player");
  EXPECT_EQ(w[0].period_ms.count, 11u);
  EXPECT_DOUBLE_EQ(w[0].period_ms.mean, 83.0);
  EXPECT_DOUBLE_EQ(w[0].latency_ms.mean, 2.0);
  EXPECT_NEAR(w[0].latency_pct_ms.p99, 2.0, 1e-9);
  EXPECT_DOUBLE_EQ(w[0].age_ms.max, 20.0);
  EXPECT_DOUBLE_EQ(w[0].size_bytes.mean, 1000.0);
  EXPECT_DOUBLE_EQ(w[0].rate_hz(), 12.0);
  EXPECT_DOUBLE_EQ(w[0].bandwidth_mb_s(), 0.012);
}

TEST(TopicStatsTest, NewWindowStartsEmptyButTotalsAccumulate) {
  TopicStatsCollector c(kNsPerSec, kStart);
  c.record("/a", "p", At(kStart + 1, 0, 10));
  c.add_transport_drops("/a", 3);
  (void)c.take_window(kStart + kNsPerSec);
  c.record("/a", "p", At(kStart + kNsPerSec + 100 * kNsPerMs, 0, 10));
  c.add_superseded("/a", 2);
  const auto w = c.take_window(kStart + 2 * kNsPerSec);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].received, 1u);
  EXPECT_EQ(w[0].transport_drops, 0u);
  EXPECT_EQ(w[0].superseded, 2u);
  EXPECT_EQ(w[0].period_ms.count, 1u);  // the period spans the window boundary
  const auto t = c.totals(kStart + 2 * kNsPerSec);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].received, 2u);
  EXPECT_EQ(t[0].transport_drops, 3u);
  EXPECT_EQ(t[0].superseded, 2u);
}

TEST(TopicStatsTest, IdleTopicsAreLeftOutOfAWindow) {
  TopicStatsCollector c(kNsPerSec, kStart);
  c.record("/a", "p", At(kStart + 1, 0, 10));
  (void)c.take_window(kStart + kNsPerSec);
  EXPECT_TRUE(c.take_window(kStart + 2 * kNsPerSec).empty());
}

TEST(TopicStatsTest, UnknownStampsSkipAgeAndLatency) {
  TopicStatsCollector c(kNsPerSec, kStart);
  Sample s;
  s.receive_mono_ns = kStart + 5;
  s.size_bytes = 4;
  c.record("/a", "p", s);
  const auto w = c.take_window(kStart + kNsPerSec);
  EXPECT_EQ(w[0].latency_ms.count, 0u);
  EXPECT_EQ(w[0].age_ms.count, 0u);
}

TEST(TopicStatsTest, FormatNamesTopicAndDrops) {
  TopicWindow w;
  w.topic = "/cam_back/x";
  w.transport_drops = 7;
  const std::string line = format(w);
  EXPECT_NE(line.find("/cam_back/x"), std::string::npos);
  EXPECT_NE(line.find("drops 7"), std::string::npos);
}

}  // namespace
}  // namespace faultline::stats
