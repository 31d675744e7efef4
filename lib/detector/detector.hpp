// The reference detector for the synthetic scenes, from pixels only: colour LUT -> connected
// components -> ground-plane lifting per camera, cross-camera merge, and (temporal mode) tracking
// over every frame.
#pragma once

#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "detector/blobs.hpp"
#include "detector/box.hpp"
#include "detector/color_lut.hpp"
#include "detector/lift.hpp"
#include "detector/photometric.hpp"
#include "detector/tracker.hpp"

namespace faultline::detector {

struct DetectorConfig {
  double scale = 1.0;  // input scale: 1.0, 0.5 or 0.25 of the full image
  bool temporal =
      true;  // track over every frame (velocity, smoothing, coasting) vs single key frame
  PhotometricConfig photometric;
  ColorLutConfig colors;
  BlobConfig blobs;
  LiftConfig lift;
  TrackerConfig tracker;
  std::string describe() const;  // "synth_color scale=0.5 temporal=1"
};

// The nuScenes devkit rejects a sample with more boxes; finish_sample keeps the highest-scoring
// ones.
constexpr std::size_t kMaxBoxesPerSample = 500;

struct CameraInput {
  std::string camera;       // "CAM_FRONT"
  cv::Mat bgr;              // CV_8UC3, full resolution or already at `scale`
  CameraGeometry geometry;  // intrinsics refer to geometry.width x geometry.height
  std::int64_t timestamp_us = 0;
};

// Merges detections of one object (same class, closer than the class merge radius): score-weighted
// centre, highest score kept and slightly raised by the extra evidence. Deterministic (sorted by
// score, then position).
std::vector<Box3d> merge_duplicates(std::vector<Box3d> boxes);

class Detector {
 public:
  explicit Detector(const DetectorConfig& config);

  // Per-camera detections (global frame), no merging. Uses the road prior learnt from earlier ego
  // poses. Not thread-safe: it reuses the detector's image buffers.
  std::vector<Box3d> detect_camera(const CameraInput& frame) const;

  // Every camera frame in capture order (sweeps and key frames). Temporal mode tracks it;
  // single-frame mode keeps it as the latest frame of its camera for the current sample.
  void add_frame(const CameraInput& frame);

  // Boxes of the sample whose key frames were added last, at `timestamp_us` (at most
  // kMaxBoxesPerSample, the highest scores); clears the per-sample frames.
  std::vector<Box3d> finish_sample(std::int64_t timestamp_us);

  const DetectorConfig& config() const { return config_; }

  // Forgets the ego-motion history (the road curvature estimate), as at start-up: for a break in
  // the stream.
  void reset_motion();

 private:
  static constexpr std::int64_t kStartOverUs =
      1'000'000;  // a frame this much older than the last: start over
  void observe_ego(const dataset::Rigid& ego_to_world, std::int64_t t_us);

  DetectorConfig config_;
  ColorLut lut_;
  struct Scratch {  // per-frame images whose buffers are reused (their page faults cost more than
                    // the work)
    cv::Mat normalised, labels;
  };
  mutable Scratch scratch_;
  Tracker tracker_;
  std::map<std::string, CameraInput> latest_;  // single-frame mode: per camera
  RoadPrior road_;
  dataset::Rigid last_ego_;     // last pose used for the curvature estimate
  dataset::Rigid current_ego_;  // pose of the latest frame
  std::int64_t last_ego_us_ = 0;
  bool have_ego_ = false;
};

}  // namespace faultline::detector
