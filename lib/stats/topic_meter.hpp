// Sliding-window meters behind `faultline topic hz|bw|delay`, plus the transport-free probe loop
// that feeds them. Rate and bandwidth come from receive times only (like `ros2 topic hz`, but the
// loop does nothing per message except store a timestamp, a size and optionally a delay, so large
// frames are counted correctly). Statistics are computed when a report is asked for, not per
// message.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "common/status.hpp"
#include "stats/histogram.hpp"

namespace faultline::stats {

constexpr DurationNs kNoDelay = std::numeric_limits<DurationNs>::min();  // sample carries no delay

struct MeterStats {
  std::uint64_t count = 0;  // messages considered (in the window, or in the whole run)
  DurationNs span_ns = 0;   // last - first receive time of those messages
  double rate_hz = 0;       // (count - 1) / span; 0 with fewer than 2 messages
  Summary period_ms;        // differences between consecutive receive times
  double bytes_per_s = 0;   // bytes of all but the first message / span (= mean size x rate)
  Summary size_bytes;
  Summary delay_ms;                           // over messages that carried a delay
  double delay_p50_ms = 0, delay_p99_ms = 0;  // nearest-rank percentiles, exact
};

// Not thread-safe; one meter per receive loop.
class TopicMeter {
 public:
  explicit TopicMeter(DurationNs window_ns = kNsPerSec);

  // receive_ns: a monotonic receive time, non-decreasing. delay_ns: now - capture stamp, or
  // kNoDelay.
  void add(StampNs receive_ns, std::uint64_t size_bytes, DurationNs delay_ns = kNoDelay);
  // Messages received in (now - window, now]; older ones are forgotten.
  MeterStats window(StampNs now_ns);
  // Every message since construction (delay percentiles keep one double per message).
  MeterStats total() const;
  std::uint64_t count() const { return count_; }

 private:
  struct Entry {
    StampNs receive_ns;
    std::uint64_t size_bytes;
    DurationNs delay_ns;
  };
  DurationNs window_ns_;
  std::deque<Entry> window_;
  std::uint64_t count_ = 0;
  StampNs first_ns_ = 0, last_ns_ = 0;
  std::uint64_t first_size_ = 0, bytes_ = 0;
  RunningSummary period_ms_, size_, delay_;
  std::vector<double> delays_ms_;
};

// Nearest-rank percentile of unsorted values (q in [0, 1]); 0 when empty. Reorders `values`.
double nearest_rank(std::vector<double>& values, double q);

// What a probe loop receives: a receive time, a size, and a delay when the caller computed one.
struct ProbeSample {
  StampNs receive_ns = 0;
  std::uint64_t size_bytes = 0;
  DurationNs delay_ns = kNoDelay;
};
// Waits up to timeout_ns for one message. kWouldBlock on timeout; kCancelled (or any other error)
// ends the probe.
using ProbeReceive = std::function<Result<ProbeSample>(DurationNs timeout_ns)>;

struct ProbeOptions {
  DurationNs window_ns = kNsPerSec;        // sliding window of the periodic reports
  DurationNs report_every_ns = kNsPerSec;  // 0 = no periodic reports
  DurationNs duration_ns = 0;              // stop after this long (from the start); 0 = no limit
  std::uint64_t max_messages = 0;          // stop after this many messages; 0 = no limit
  DurationNs poll_ns = 50 * kNsPerMs;      // receive timeout; bounds the reaction to `stop`
};

enum class ProbeEnd { Stopped, Duration, MessageCount, ReceiveError };
const char* to_string(ProbeEnd end);

struct ProbeResult {
  MeterStats total;
  ProbeEnd end = ProbeEnd::Stopped;
  std::string error;  // when end == ReceiveError
  DurationNs elapsed_ns = 0;
};

// Receives until stop, duration or count; calls on_report(window stats) every report_every_ns.
// `now` is the clock used for reports and the duration (monotonic, same base as receive_ns).
ProbeResult run_probe(const ProbeReceive& receive, const ProbeOptions& options,
                      const std::atomic<bool>& stop,
                      const std::function<void(const MeterStats&)>& on_report,
                      const std::function<StampNs()>& now = monotonic_now_ns);

// Report lines in the style of ros2 topic hz/bw/delay.
std::string format_hz(const MeterStats& s);
std::string format_bw(const MeterStats& s);
std::string format_delay(const MeterStats& s);
// One key=value line for scripts: count, span, rate, period, bandwidth, size and (if any) delay.
std::string format_summary(const std::string& topic, const MeterStats& s);

}  // namespace faultline::stats
