// Helpers for transport tests: a unique ipc path and a bounded wait without sleeping on a timer.
#pragma once

#include <unistd.h>

#include <atomic>
#include <functional>
#include <string>
#include <thread>

#include "common/clock.hpp"

namespace faultline::transport::testing {

inline std::string unique_ipc(const std::string& stem) {
  static std::atomic<int> counter{0};
  return "ipc:///tmp/faultline-test-" + stem + "-" + std::to_string(::getpid()) + "-" +
         std::to_string(counter++);
}

// Spins (yielding) until `done` or the deadline; true when `done` turned true.
inline bool eventually(const std::function<bool()>& done, DurationNs timeout_ns = 5 * kNsPerSec) {
  const StampNs deadline = monotonic_now_ns() + timeout_ns;
  while (!done()) {
    if (monotonic_now_ns() > deadline) return false;
    std::this_thread::yield();
  }
  return true;
}

}  // namespace faultline::transport::testing
