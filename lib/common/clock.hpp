// Time in Faultline is int64 nanoseconds. Clocks are injected so loops and tests control time.
#pragma once

#include <cstdint>
#include <functional>

namespace faultline {

using StampNs = std::int64_t;
using DurationNs = std::int64_t;

constexpr DurationNs kNsPerMs = 1'000'000;
constexpr DurationNs kNsPerSec = 1'000'000'000;

StampNs realtime_now_ns();   // CLOCK_REALTIME: stamps that are stored or displayed
StampNs monotonic_now_ns();  // CLOCK_MONOTONIC: latency between processes on one host

// The one source of time for node loops: pacing, timeouts, statistics windows and the stamps put on
// the wire all read it, so a test drives a loop's time exactly. SystemClock in production, a manual
// one in tests.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual StampNs now_ns() const = 0;                 // monotonic
  virtual StampNs realtime_ns() const = 0;            // wall clock, for stamps stored or displayed
  virtual void sleep_until_ns(StampNs deadline) = 0;  // now_ns() time; may return early
};

class SystemClock final : public Clock {
 public:
  StampNs now_ns() const override { return monotonic_now_ns(); }
  StampNs realtime_ns() const override { return realtime_now_ns(); }
  void sleep_until_ns(StampNs deadline) override;
};

// One SystemClock for the process: the default of loops constructed without a clock.
Clock& system_clock();

}  // namespace faultline
