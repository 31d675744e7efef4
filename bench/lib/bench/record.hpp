// `faultline bench record`: recorder CPU for N cameras x R Hz of JPEG frames over ipc (the recorder
// thread, and the whole process), player speed (rate 0 into a draining subscriber) and bag size
// versus the raw message bytes.
#pragma once

#include <string>

#include "bench/frames.hpp"

namespace faultline::bench {

struct RecordOptions {
  double seconds = 5;         // recording length per rep
  double rate_hz = 12;        // frames per second per camera
  int cameras = 6;            // 1..6
  int reps = 3;               // repetitions; medians are printed
  bool foxglove_view = true;  // also the recorder's Foxglove view channels
  std::string images;  // folder of JPEGs to send (first N, one per camera); "" = built-in frames
  FrameKind frames = FrameKind::kRealistic;  // built-in frames (bench/frames.hpp)
  bool noise = false;                        // the older spelling of frames = kNoisy
  std::string compression = "lz4";  // recorder compression: none | zstd | lz4 (its default)
};

// Prints one line per rep and the medians on stdout. Returns the exit code: 0; 1 when a frame
// cannot be encoded; 2 when --images holds no readable JPEG.
int run_record(const RecordOptions& o);

}  // namespace faultline::bench
