// A val-sized synthetic nuScenes dataset for benchmarking the scorer: the devkit's 150 val scene
// names, 6,019 samples (~40 per scene) with LIDAR_TOP key-frame sample_data + ego poses, ~50
// annotated, tracked objects per sample (prev/next links, attributes, bike racks), and a matching
// noisy submission.
#pragma once

#include <cstdint>
#include <string>

#include "common/status.hpp"

namespace faultline::bench {

struct SyntheticValConfig {
  int samples = 6019;  // total key frames over the 150 val scenes
  bool full_trainval =
      true;  // also the 700 train scenes (28,130 samples), as the real tables hold them
  int train_samples = 28130;
  int train_objects_per_scene = 35;  // ~1.2 M annotations in all, like v1.0-trainval
  bool sweeps = true;  // every sample_data record: 6 cameras at 12 Hz, LIDAR 20 Hz, 5 radars 13 Hz
  int objects_per_scene = 50;     // tracked objects, each annotated in every sample
  double detection_rate = 0.9;    // fraction of GT boxes the fake detector finds
  int false_positives = 5;        // extra boxes per sample
  std::uint64_t seed = 20240607;  // deterministic output
};

struct SyntheticValStats {
  int scenes = 0, samples = 0;
  std::size_t annotations = 0, predictions = 0, sample_data = 0;
};

// Writes <dir>/v1.0-trainval/*.json and <dir>/results.json.
Result<SyntheticValStats> write_synthetic_val(const std::string& dir,
                                              const SyntheticValConfig& cfg = {});

}  // namespace faultline::bench
