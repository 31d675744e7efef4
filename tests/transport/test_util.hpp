// Helpers for transport tests: a unique ipc path, a bounded wait without sleeping on a timer, and
// a capture of what the library logs.
#pragma once

#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <memory>
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

// Captures what `logger` (by default spdlog's default logger, which the transport's
// logging::node_logger() is when no node logger was made) logs for the life of the capture.
class LogCapture {
 public:
  explicit LogCapture(std::shared_ptr<spdlog::logger> logger = spdlog::default_logger())
      : logger_(std::move(logger)),
        ring_(std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(256)) {
    ring_->set_pattern("%l %v");
    logger_->sinks().push_back(ring_);
  }
  ~LogCapture() {
    auto& sinks = logger_->sinks();
    sinks.erase(std::remove(sinks.begin(), sinks.end(), ring_), sinks.end());
  }
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;
  // Lines containing `needle`.
  int count(const std::string& needle) const {
    int n = 0;
    for (const auto& line : ring_->last_formatted())
      n += line.find(needle) != std::string::npos ? 1 : 0;
    return n;
  }
  // Lines logged at `level` ("error", "warning", ...) containing `needle`.
  int count_at(const std::string& level, const std::string& needle) const {
    int n = 0;
    for (const auto& line : ring_->last_formatted()) {
      n += line.rfind(level + " ", 0) == 0 && line.find(needle) != std::string::npos ? 1 : 0;
    }
    return n;
  }
  std::string all() const {
    std::string text;
    for (const auto& line : ring_->last_formatted()) text += line;
    return text;
  }

 private:
  std::shared_ptr<spdlog::logger> logger_;
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> ring_;
};

}  // namespace faultline::transport::testing
