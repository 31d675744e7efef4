// A stand-in detector for pipeline tests: subscribes to the faulted camera topics and /sync/sample,
// validates every frame and pushes one DetectionArray (one box) per sample boundary to the sink.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <string>

#include "transport/drop_counter.hpp"

namespace faultline::runtime::testing {

struct FakeDetectorResult {
  std::uint64_t frames = 0;  // valid frames received
  std::uint64_t malformed = 0;
  std::uint64_t boundaries = 0;
  std::uint64_t transport_drops = 0;  // from seq gaps per (publisher, topic)
  std::map<std::string, std::uint64_t> frames_per_topic;
  bool saw_last = false;
};

class FakeDetector {
 public:
  // Connects now (so publishers can wait for it); run() serves until last_in_run or `stop`.
  FakeDetector(const std::string& input_endpoint, const std::string& sink_endpoint, int hwm = 64);
  ~FakeDetector();
  FakeDetectorResult run(const std::atomic<bool>& stop);

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace faultline::runtime::testing
