// `faultline bench bag`: write/read throughput of a 6-camera recording and stored vs raw size per
// compression, on the benchmarks' 1600x900 frames (bench/frames.hpp: realistic q90 JPEGs of 130-165
// KB, or the noisy worst case near 400 KB) and on their decoded raw bgr8.
#pragma once

#include <string>

#include "bench/frames.hpp"

namespace faultline::bench {

struct BagOptions {
  int seconds = 60;     // seconds of JPEG data per run (6 cameras x 12 Hz)
  int raw_seconds = 1;  // seconds of raw bgr8 data per run
  int repeats = 3;      // runs per configuration; medians are reported
  std::string dir;      // scratch directory for the bags, each deleted after its run; "" = temp dir
  FrameKind frames =
      FrameKind::kRealistic;  // noisy: the road scene at noise 32, JPEG quality nearest 400 KB
};

// Prints the table on stdout. Returns the exit code: 0, or 1 (message on stderr) when a bag cannot
// be written.
int run_bag(const BagOptions& o);

}  // namespace faultline::bench
