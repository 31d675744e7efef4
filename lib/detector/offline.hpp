// The reference detector run offline over a nuScenes-format dataset (`faultline detect`): every
// camera frame of the chosen scenes, optionally corrupted (fast RNG mode, per frame seed + frame
// index), detections per sample for `faultline score`.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "corruption/types.hpp"
#include "detector/box.hpp"
#include "detector/detector.hpp"

namespace faultline::detector {

struct OfflineDetectOptions {
  std::string dataroot;
  std::string version = "v1.0-mini";
  std::vector<std::string> scenes;  // empty: every scene of the version
  DetectorConfig detector;
  std::optional<corruption::Corruption> corruption;  // none: the frames as stored
  int severity = 0;
  std::uint64_t seed = 0;  // the corruption of frame i draws from seed + i
};

struct OfflineDetectResult {
  std::map<std::string, std::vector<Box3d>>
      detections;  // every sample of the scenes (may be empty)
  // Detector time per camera frame (ms): each frame in temporal mode, else each key-frame sample's
  // time shared by its six cameras.
  std::vector<double> frame_ms;
};

// Runs the detector, reset per scene (tracks never cross scenes). Errors: the dataset's, and an
// unreadable or undecodable image named by its path.
Result<OfflineDetectResult> detect_dataset(const OfflineDetectOptions& options);

}  // namespace faultline::detector
