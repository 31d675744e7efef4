// A clock for tests: time moves only when the test advances it or the code under test sleeps, so
// stamps and timing decisions are exact and nothing waits for real.
#pragma once

#include <algorithm>
#include <atomic>
#include <mutex>
#include <vector>

#include "common/clock.hpp"

namespace faultline {

class ManualClock final : public Clock {
 public:
  // realtime_ns() is now_ns() + `realtime_offset_ns`.
  explicit ManualClock(StampNs start_ns = 1000 * kNsPerSec,
                       StampNs realtime_offset_ns = 1'700'000'000 * kNsPerSec)
      : now_(start_ns), offset_(realtime_offset_ns) {}

  StampNs now_ns() const override { return now_.load(); }
  StampNs realtime_ns() const override { return now_.load() + offset_; }
  // Jumps to `deadline` (never back) and remembers it, so a test can check every sleep.
  void sleep_until_ns(StampNs deadline) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      sleeps_.push_back(deadline);
    }
    advance_to(deadline);
  }

  void advance_to(StampNs t) {
    StampNs cur = now_.load();
    while (t > cur && !now_.compare_exchange_weak(cur, t)) {
    }
  }
  void advance_by(DurationNs d) { now_.fetch_add(d); }
  std::vector<StampNs> sleeps() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return sleeps_;
  }

 private:
  std::atomic<StampNs> now_;
  const StampNs offset_;
  mutable std::mutex mutex_;
  std::vector<StampNs> sleeps_;
};

}  // namespace faultline
