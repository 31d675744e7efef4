// `faultline bench bag-corrupt`: `bag corrupt` frames/s on 1 and 2 threads against `faultline
// export` on the same frames: the key-frame camera JPEGs of a synthetic nuScenes dataset, exported
// as one condition and, as a rosbag2 bag of CompressedImage topics (one per camera), corrupted with
// the same fault. Runs alternate tool and thread count so both see the same machine load; medians
// over the repetitions.
#pragma once

#include <string>

namespace faultline::bench {

struct BagCorruptBenchOptions {
  std::string work_dir;            // scratch folder; "" = a fresh one under the temp dir, removed
  int reps = 3;                    // runs per (tool, threads); medians are reported
  int scenes = 1;                  // synthetic scenes
  double seconds = 4.0;            // seconds per scene, key frames at 2 Hz (6 cameras each)
  int width = 1600, height = 900;  // image size in pixels
  std::string fault = "fog";       // an image corruption (export condition and bag corrupt TYPE)
  std::string level = "mid";       // easy, mid or hard
  std::string rng = "fast";        // numpy or fast
};

// Prints the table on stdout. Returns 0; 2 for a bad option value; 1 when the dataset, bag or a run
// fails.
int run_bag_corrupt_bench(const BagCorruptBenchOptions& o);

}  // namespace faultline::bench
