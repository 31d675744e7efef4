// `faultline bench ros2`: the ROS 2 proxy (ros2_in -> fault_injector -> ros2_out, the real node
// processes as launch/ros2_proxy.yaml composes them) under N cameras x rate_hz of 1600x900 JPEG
// CompressedImages published over Cyclone DDS on loopback, passthrough and with one corruption,
// alternating run by run (side by side). Per run: frames in/out, unintended drops, added latency
// p50/p99 (DDS write of the original -> DDS receipt of the faulted copy, both in this process: an
// upper bound, as it includes the two DDS hops a direct subscriber would also pay), and the nodes'
// CPU.
#pragma once

#include <string>

#include "bench/frames.hpp"

namespace faultline::bench {

struct Ros2Options {
  double seconds = 20;  // real-time duration of each run (> 0)
  double rate_hz = 12;  // frames per second per camera (> 0)
  int cameras = 6;      // 1..6
  int width = 1600;     // frame size (pixels)
  int height = 900;
  FrameKind frames =
      FrameKind::kRealistic;  // bench/frames.hpp: realistic (q90, 130-165 KB) or noisy
  bool cameras_together =
      false;      // all cameras fire at once (worst case) instead of staggered as the rig
  int noise = 2;  // noisy frames' noise: 2 gives ~380 KB at q95, 6 the worst case (~550 KB)
  std::string corruption =
      "brightness/mid";           // the corrupted configuration (injector `corruption` shorthand)
  int repeats = 3;                // runs per configuration (medians and ranges reported)
  int domain_id = -1;             // -1: 100 + pid % 100 (a domain no real ROS 2 graph uses)
  std::string bin_dir;            // ros2_in, fault_injector, ros2_out; "" = next to this executable
  std::string work_dir = "/tmp";  // parameters, sockets and node logs (a fresh directory per run)
  bool json = false;              // print a JSON object instead of the table
};

// Prints one line per run and a summary (or JSON) on stdout. Returns 0; 1 when a run fails to
// start; 3 when a passthrough run had unintended drops.
int run_ros2(const Ros2Options& o);

}  // namespace faultline::bench
