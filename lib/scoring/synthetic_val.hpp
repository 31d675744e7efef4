// A val-sized synthetic nuScenes dataset for benchmarking the scorer: the devkit's 150 val scene names,
// 6,019 samples (~40 per scene) with LIDAR_TOP key-frame sample_data + ego poses, ~50 annotated, tracked
// objects per sample (prev/next links, attributes, bike racks), and a matching noisy submission.
#pragma once

#include <cstdint>
#include <string>

#include "common/status.hpp"

namespace faultline::scoring {

struct SyntheticValConfig {
  int samples = 6019;             // total key frames over the 150 val scenes
  int objects_per_scene = 50;     // tracked objects, each annotated in every sample
  double detection_rate = 0.9;    // fraction of GT boxes the fake detector finds
  int false_positives = 5;        // extra boxes per sample
  std::uint64_t seed = 20240607;  // deterministic output
};

struct SyntheticValStats {
  int scenes = 0, samples = 0;
  std::size_t annotations = 0, predictions = 0;
};

// Writes <dir>/v1.0-trainval/*.json and <dir>/results.json.
Result<SyntheticValStats> write_synthetic_val(const std::string& dir, const SyntheticValConfig& cfg = {});

}  // namespace faultline::scoring
