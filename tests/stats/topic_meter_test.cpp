// TopicMeter math and the probe loop, with injected receive times and clock (no real time).
#include "stats/topic_meter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace faultline::stats {
namespace {

constexpr StampNs kStart = 5 * kNsPerSec;  // arbitrary monotonic origin

StampNs Ms(double ms) { return kStart + static_cast<StampNs>(ms * 1e6); }

class TopicMeterTest : public ::testing::Test {
 protected:
  void ReceiveAtMs(std::initializer_list<double> times_ms, std::uint64_t size_bytes = 1000) {
    for (double t : times_ms) meter_.add(Ms(t), size_bytes);
  }
  void ReceiveEvery(double period_ms, int n, std::uint64_t size_bytes = 1000) {
    for (int i = 0; i < n; ++i) meter_.add(Ms(period_ms * i), size_bytes);
  }
  static void ExpectRate(const MeterStats& s, std::uint64_t count, double rate_hz,
                         double period_mean_ms, double period_std_ms) {
    EXPECT_EQ(s.count, count);
    EXPECT_NEAR(s.rate_hz, rate_hz, 1e-6);
    EXPECT_NEAR(s.period_ms.mean, period_mean_ms, 1e-6);
    EXPECT_NEAR(s.period_ms.stddev, period_std_ms, 1e-3);
  }

  TopicMeter meter_{kNsPerSec};
};

TEST_F(TopicMeterTest, SteadyStreamGivesExactRateAndNoJitter) {
  ReceiveAtMs({0, 10, 20, 30, 40});
  ExpectRate(meter_.total(), /*count=*/5, /*rate_hz=*/100, /*period_mean_ms=*/10,
             /*period_std_ms=*/0);
  EXPECT_DOUBLE_EQ(meter_.total().period_ms.min, 10);
  EXPECT_DOUBLE_EQ(meter_.total().period_ms.max, 10);
}

TEST_F(TopicMeterTest, JitteredPeriodsGiveMinMaxAndStd) {
  ReceiveAtMs({0, 10, 30, 40});  // periods 10, 20, 10
  ExpectRate(meter_.total(), 4, /*rate_hz=*/75, /*mean=*/40.0 / 3, /*std=*/4.714);
  EXPECT_DOUBLE_EQ(meter_.total().period_ms.min, 10);
  EXPECT_DOUBLE_EQ(meter_.total().period_ms.max, 20);
}

TEST_F(TopicMeterTest, SeventyTwoHertzIsMeasuredAsSeventyTwo) {
  for (int i = 0; i < 144; ++i) meter_.add(kStart + i * kNsPerSec / 72, 4'320'000);
  EXPECT_NEAR(meter_.total().rate_hz, 72.0, 1e-3);
  EXPECT_NEAR(meter_.total().bytes_per_s, 72.0 * 4'320'000, 1e3);
}

TEST_F(TopicMeterTest, WindowKeepsOnlyRecentMessages) {
  ReceiveEvery(10, 200);  // 0 .. 1990 ms
  const MeterStats w = meter_.window(Ms(1995));
  ExpectRate(w, /*count=*/100, /*rate_hz=*/100, /*mean=*/10, /*std=*/0);  // 1000 .. 1990 ms
  EXPECT_EQ(meter_.total().count, 200u);
}

TEST_F(TopicMeterTest, WindowIsEmptyAfterSilenceButTotalsRemain) {
  ReceiveEvery(10, 50);
  const MeterStats w = meter_.window(Ms(3000));
  EXPECT_EQ(w.count, 0u);
  EXPECT_EQ(w.rate_hz, 0);
  EXPECT_EQ(format_hz(w), "no new messages");
  EXPECT_NEAR(meter_.total().rate_hz, 100, 1e-6);
}

TEST_F(TopicMeterTest, SingleMessageHasNoRate) {
  ReceiveAtMs({0});
  EXPECT_EQ(meter_.total().count, 1u);
  EXPECT_EQ(meter_.total().rate_hz, 0);
  EXPECT_EQ(meter_.total().bytes_per_s, 0);
}

TEST_F(TopicMeterTest, BandwidthCountsBytesAfterTheFirstMessageOverTheSpan) {
  meter_.add(Ms(0), 500);
  meter_.add(Ms(100), 1000);
  meter_.add(Ms(200), 3000);
  const MeterStats s = meter_.total();
  EXPECT_NEAR(s.bytes_per_s, 4000 / 0.2, 1e-6);
  EXPECT_DOUBLE_EQ(s.size_bytes.mean, 1500);
  EXPECT_DOUBLE_EQ(s.size_bytes.min, 500);
  EXPECT_DOUBLE_EQ(s.size_bytes.max, 3000);
}

TEST_F(TopicMeterTest, DelayPercentilesAreNearestRank) {
  std::vector<int> delays_ms(100);
  for (int i = 0; i < 100; ++i) delays_ms[static_cast<std::size_t>(i)] = i + 1;
  std::shuffle(delays_ms.begin(), delays_ms.end(), std::mt19937(7));
  for (int i = 0; i < 100; ++i)
    meter_.add(Ms(i), 10, delays_ms[static_cast<std::size_t>(i)] * kNsPerMs);
  const MeterStats s = meter_.total();
  EXPECT_DOUBLE_EQ(s.delay_p50_ms, 50);
  EXPECT_DOUBLE_EQ(s.delay_p99_ms, 99);
  EXPECT_DOUBLE_EQ(s.delay_ms.min, 1);
  EXPECT_DOUBLE_EQ(s.delay_ms.max, 100);
  EXPECT_EQ(meter_.window(Ms(99)).delay_ms.count, 100u);
}

TEST_F(TopicMeterTest, MessagesWithoutDelayDoNotEnterDelayStats) {
  meter_.add(Ms(0), 10);
  meter_.add(Ms(1), 10, 7 * kNsPerMs);
  EXPECT_EQ(meter_.total().delay_ms.count, 1u);
  EXPECT_DOUBLE_EQ(meter_.total().delay_p99_ms, 7);
}

struct RankRow {
  std::vector<double> values;
  double q;
  double expected;
};

class NearestRankTest : public ::testing::TestWithParam<RankRow> {};

TEST_P(NearestRankTest, MatchesTable) {
  std::vector<double> v = GetParam().values;
  EXPECT_DOUBLE_EQ(nearest_rank(v, GetParam().q), GetParam().expected);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, NearestRankTest,
    ::testing::Values(RankRow{{}, 0.5, 0}, RankRow{{3}, 0.99, 3}, RankRow{{4, 1, 3, 2}, 0.5, 2},
                      RankRow{{4, 1, 3, 2}, 0.75, 3}, RankRow{{4, 1, 3, 2}, 0.76, 4},
                      RankRow{{4, 1, 3, 2}, 0.0, 1}, RankRow{{4, 1, 3, 2}, 1.0, 4}));

// A scripted receive: returns the samples at their times and otherwise lets the fake clock run.
class ProbeTest : public ::testing::Test {
 protected:
  ProbeResult Run(const ProbeOptions& options) {
    std::size_t next = 0;
    const ProbeReceive receive = [&](DurationNs timeout_ns) -> Result<ProbeSample> {
      if (next < samples_.size() && samples_[next].receive_ns <= now_ + timeout_ns) {
        now_ = std::max(now_, samples_[next].receive_ns);
        return samples_[next++];
      }
      if (next >= samples_.size() && cancel_when_exhausted_)
        return Status{StatusCode::kCancelled, "ctx"};
      now_ += timeout_ns;
      return Status{StatusCode::kWouldBlock, "timeout"};
    };
    return run_probe(
        receive, options, stop_, [&](const MeterStats& s) { reports_.push_back(s); },
        [&] { return now_; });
  }
  void SamplesEveryMs(double period_ms, int n) {
    for (int i = 0; i < n; ++i) samples_.push_back({Ms(period_ms * (i + 1)), 100, kNoDelay});
  }

  StampNs now_ = kStart;
  std::vector<ProbeSample> samples_;
  std::vector<MeterStats> reports_;
  std::atomic<bool> stop_{false};
  bool cancel_when_exhausted_ = false;
};

TEST_F(ProbeTest, StopsAfterMessageCount) {
  SamplesEveryMs(10, 50);
  ProbeOptions o;
  o.max_messages = 20;
  const auto r = Run(o);
  EXPECT_EQ(r.end, ProbeEnd::MessageCount);
  EXPECT_EQ(r.total.count, 20u);
  EXPECT_NEAR(r.total.rate_hz, 100, 1e-6);
}

TEST_F(ProbeTest, StopsAfterDurationAndReportsEverySecond) {
  SamplesEveryMs(10, 1000);  // 10 s of 100 Hz
  ProbeOptions o;
  o.duration_ns = 3 * kNsPerSec;
  const auto r = Run(o);
  EXPECT_EQ(r.end, ProbeEnd::Duration);
  ASSERT_EQ(reports_.size(), 3u);
  for (const auto& w : reports_) EXPECT_NEAR(w.rate_hz, 100, 1e-6);
  EXPECT_NEAR(static_cast<double>(r.total.count), 300, 1);
}

TEST_F(ProbeTest, ReportsSilenceAsEmptyWindows) {
  SamplesEveryMs(10, 10);  // 0.1 s of data, then nothing
  ProbeOptions o;
  o.duration_ns = 2500 * kNsPerMs;
  const auto r = Run(o);
  ASSERT_EQ(reports_.size(), 2u);
  EXPECT_EQ(reports_[0].count, 10u);
  EXPECT_EQ(reports_[1].count, 0u);
  EXPECT_EQ(r.total.count, 10u);
}

TEST_F(ProbeTest, CancelledReceiveEndsAsStopped) {
  SamplesEveryMs(10, 5);
  cancel_when_exhausted_ = true;
  const auto r = Run(ProbeOptions{});
  EXPECT_EQ(r.end, ProbeEnd::Stopped);
  EXPECT_EQ(r.total.count, 5u);
}

TEST_F(ProbeTest, StopFlagEndsBeforeReceiving) {
  SamplesEveryMs(10, 5);
  stop_.store(true);
  const auto r = Run(ProbeOptions{});
  EXPECT_EQ(r.end, ProbeEnd::Stopped);
  EXPECT_EQ(r.total.count, 0u);
}

TEST(FormatTest, SummaryLineHasKeyValues) {
  TopicMeter m;
  m.add(Ms(0), 2000, 3 * kNsPerMs);
  m.add(Ms(500), 2000, 5 * kNsPerMs);
  const std::string line = format_summary("/cam_front/image", m.total());
  EXPECT_EQ(line.rfind("summary topic=/cam_front/image count=2 span_s=0.500 rate_hz=2.000", 0), 0u)
      << line;
  EXPECT_NE(line.find("bw_mb_s=0.004"), std::string::npos) << line;
  EXPECT_NE(line.find("delay_ms_p50=3.000 delay_ms_p99=5.000"), std::string::npos) << line;
}

}  // namespace
}  // namespace faultline::stats
