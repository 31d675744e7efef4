// Per-topic statistics over a window (default 1 s) and over the whole run: period, age
// (receive - capture stamp, realtime), size, hop latency (receive - publish, monotonic) and drop
// counts. The owner feeds samples and drop counts; it decides when to take a window (log it,
// publish it as TopicStats on /statistics). Not thread-safe: one collector per loop.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "stats/histogram.hpp"

namespace faultline::stats {

struct Sample {
  StampNs receive_mono_ns = 0;  // CLOCK_MONOTONIC at receive (or send, for a publisher's own view)
  StampNs receive_realtime_ns = 0;  // CLOCK_REALTIME at receive
  StampNs capture_stamp_ns = 0;     // header.capture_stamp_ns; 0 = unknown (no age)
  StampNs publish_mono_ns = 0;      // header.publish_mono_ns; 0 = unknown (no latency)
  std::uint64_t size_bytes = 0;
};

struct TopicWindow {
  std::string topic;
  std::string publisher;
  DurationNs window_ns = 0;
  std::uint64_t received = 0;
  std::uint64_t transport_drops = 0;
  std::uint64_t superseded = 0;
  std::uint64_t injected_drops = 0;
  std::uint64_t malformed = 0;
  Summary period_ms, age_ms, size_bytes, latency_ms;
  Percentiles latency_pct_ms, age_pct_ms;
  double rate_hz() const;
  double bandwidth_mb_s() const;  // 1 MB = 1e6 bytes
};

// "/cam_front/x from nusc_player: 12.0 Hz, 5.2 MB/s, latency p50 1.10 ms p95 .. p99 .. max .., ..."
std::string format(const TopicWindow& w);

class TopicStatsCollector {
 public:
  explicit TopicStatsCollector(DurationNs window_ns = kNsPerSec,
                               StampNs start_mono_ns = monotonic_now_ns());

  void record(const std::string& topic, const std::string& publisher, const Sample& sample);
  void add_transport_drops(const std::string& topic, std::uint64_t n);
  void add_superseded(const std::string& topic, std::uint64_t n);
  void add_injected_drops(const std::string& topic, std::uint64_t n);
  void add_malformed(const std::string& topic, std::uint64_t n);

  bool window_elapsed(StampNs now_mono_ns) const {
    return now_mono_ns - window_start_ns_ >= window_ns_;
  }
  // The current window per topic (topics with any activity), then starts a new window.
  std::vector<TopicWindow> take_window(StampNs now_mono_ns);
  // Totals over the whole run (since construction).
  std::vector<TopicWindow> totals(StampNs now_mono_ns) const;

 private:
  struct Accumulator {
    std::string publisher;
    std::uint64_t received = 0, transport_drops = 0, superseded = 0, injected_drops = 0,
                  malformed = 0;
    RunningSummary period_ms, age_ms, size_bytes, latency_ms;
    LogHistogram latency_hist, age_hist;
    StampNs last_receive_ns = 0;
    TopicWindow finish(const std::string& topic, DurationNs window_ns) const;
    void reset_window();
  };
  struct TopicState {
    Accumulator window, run;
  };
  TopicState& state(const std::string& topic) { return topics_[topic]; }

  DurationNs window_ns_;
  StampNs window_start_ns_;
  StampNs run_start_ns_;
  std::map<std::string, TopicState> topics_;
};

}  // namespace faultline::stats
