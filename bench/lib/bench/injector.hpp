// `faultline bench injector`: 6 cameras x rate_hz of JPEG frames through the real InjectorLoop (ipc), decode + one
// corruption per run, paced in real time: the injector thread's CPU, p50/p99 added latency, unintended drops.
#pragma once

#include <string>
#include <vector>

namespace faultline::bench {

struct InjectorOptions {
  double seconds = 10;   // real-time duration of each run (> 0)
  double rate_hz = 12;   // frames per second per camera (> 0)
  std::string level = "mid";  // easy | mid | hard
  std::vector<std::string> types = {"none", "brightness", "dark", "fog", "snow", "motion_blur", "color_quant"};
                         // corruptions, one run each; "none" = decode only
  std::string output = "bgr8";  // bgr8 (republish decoded) or jpeg (re-encode q95)
  std::vector<std::string> images;  // JPEG files to stream (camera k sends file k mod count); empty = built-in scene
  bool json = false;     // print a JSON array (the frame line then goes to stderr)
};

// Prints one line per run (or the JSON array) on stdout. Returns the exit code: 0; 2 when an --images file cannot be
// read or decoded; 1 when a run fails; 3 when a run had unintended drops.
int run_injector(const InjectorOptions& o);

}  // namespace faultline::bench
