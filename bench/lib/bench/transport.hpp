// `faultline bench transport`: 6 cameras x 12 Hz of 1600x900 JPEG frames through player ->
// injector (pass-through, optionally decoded to bgr8) -> subscriber, as loops in threads of this
// process over ipc, in real time: frames per second, per-hop and end-to-end latency p50/p99, CPU
// per frame and unintended drops.
#pragma once

#include <string>

#include "bench/frames.hpp"

namespace faultline::bench {

struct TransportOptions {
  double seconds = 10;        // run length in seconds (real time)
  std::string mode = "bgr8";  // injector output: bgr8 (decode) or jpeg (passthrough)
  bool json = false;          // print one JSON object instead of the text
  FrameKind frames =
      FrameKind::kRealistic;  // bench/frames.hpp; noisy: the road scene at noise 11, q90 (~440 KB)
};

// Prints the figures on stdout. Returns the exit code: 0, or 1 when frames were lost
// unintentionally.
int run_transport(const TransportOptions& o);

}  // namespace faultline::bench
