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

// A clock interface for loops that pace or time out; SystemClock in production, a manual one in
// tests.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual StampNs now_ns() const = 0;                 // monotonic
  virtual void sleep_until_ns(StampNs deadline) = 0;  // may return early on shutdown
};

class SystemClock final : public Clock {
 public:
  StampNs now_ns() const override { return monotonic_now_ns(); }
  void sleep_until_ns(StampNs deadline) override;
};

}  // namespace faultline
