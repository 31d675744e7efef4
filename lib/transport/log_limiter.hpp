// Rate limiting for hot-path warnings: at most one line per interval, reporting how many were held
// back.
#pragma once

#include <cstdint>

#include "common/clock.hpp"

namespace faultline::transport {

class LogLimiter {
 public:
  explicit LogLimiter(DurationNs interval_ns = kNsPerSec) : interval_ns_(interval_ns) {}
  // True when a line may be logged now; `suppressed()` then tells how many calls were held back
  // since the last line (reset on the next allowed call).
  bool allow() {
    const StampNs now = monotonic_now_ns();
    if (last_ns_ != 0 && now - last_ns_ < interval_ns_) {
      ++held_;
      return false;
    }
    suppressed_ = held_;
    held_ = 0;
    last_ns_ = now;
    return true;
  }
  std::uint64_t suppressed() const { return suppressed_; }

 private:
  DurationNs interval_ns_;
  StampNs last_ns_ = 0;
  std::uint64_t held_ = 0;
  std::uint64_t suppressed_ = 0;
};

}  // namespace faultline::transport
