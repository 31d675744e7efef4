// `faultline bench corrupt`: single-threaded median ms of every corruption x level in fast and
// numpy modes on the synthetic frame (or a given image), against the TurboJPEG decode of the same
// frame, and optionally the fidelity of fast mode against numpy mode.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bench/frames.hpp"

namespace faultline::bench {

struct CorruptOptions {
  int reps = 9;            // timed runs per case after one warm-up; the median is reported
  std::string image_path;  // "" = a built-in frame (frames.hpp) at width x height
  FrameKind frames = FrameKind::kRealistic;  // the built-in frame: realistic (decoded q90 JPEG) or
                                             // noisy (worst case)
  int width = 1600, height = 900;            // pixels of the built-in frame
  std::uint32_t seed = 130;                  // seed of the random corruptions
  std::vector<std::string> only;             // corruption types to run; empty = all
  std::vector<int> severities;  // fast mode only at these severities (1..5); empty = the levels
  bool json = false;            // print a JSON array instead of the table
  bool fidelity = false;        // also PSNR / max abs diff of fast mode against numpy mode
  std::string out_path;         // also write the JSON array (with fidelity) here; "" = none
};

// Prints the table (or the JSON array) on stdout. Returns the exit code: 0, or 1 (message on
// stderr) when the image cannot be read, the frame cannot be encoded or out_path cannot be written.
int run_corrupt(const CorruptOptions& o);

}  // namespace faultline::bench
