// `faultline bench injector`: 6 cameras x rate_hz of JPEG frames through the real InjectorLoop
// (ipc), decode + one corruption per run, paced in real time (or closed-loop, as fast as it goes):
// frames/s, the injector threads' CPU, p50/p99 added latency and unintended drops, per worker count
// side by side.
#pragma once

#include <string>
#include <vector>

#include "bench/frames.hpp"

namespace faultline::bench {

struct InjectorOptions {
  double seconds = 10;  // real-time duration of each run (> 0)
  double rate_hz =
      12;  // frames per second per camera; 0 = closed loop (4 frames per worker outstanding)
  std::vector<int> workers = {
      1};                     // injector worker threads, one run each (0 = the injector's default)
  std::string level = "mid";  // easy | mid | hard
  int severity = 0;           // 1..5: this severity instead of `level` (0 = use `level`)
  std::string output = "bgr8";  // bgr8 (republish decoded) or jpeg (re-encode q95)
  bool json = false;            // print a JSON array (the frames line then goes to stderr)
  // Corruptions, one run each; "none" = decode only.
  std::vector<std::string> types = {"none", "brightness",  "dark",       "fog",
                                    "snow", "motion_blur", "color_quant"};
  // Also run each corruption (not "none") with `coherent: true` (one persistent CoherentCorruptor
  // per camera), right after its non-coherent fast form, so the two share the machine's load of the
  // moment.
  bool coherent = false;
  // JPEG files to stream (camera k sends file k mod count); empty = built-in frames of this kind
  // (noisy: the road scene at noise 2, q95, ~370 KB, the frames of the earlier figures).
  std::vector<std::string> images;
  FrameKind frames = FrameKind::kRealistic;
};

// Prints one line per run (or the JSON array) on stdout. Returns the exit code: 0; 2 when an
// images file cannot be read or decoded; 1 when a run fails; 3 when a run had unintended drops.
int run_injector(const InjectorOptions& o);

}  // namespace faultline::bench
