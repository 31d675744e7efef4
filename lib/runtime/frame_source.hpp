// Where the player's frames come from: an abstract source so tests can replay from memory.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "camera_frame.pb.h"
#include "common/status.hpp"
#include "dataset/nuscenes.hpp"

namespace faultline::runtime {

using ImageBytes = std::shared_ptr<const std::vector<std::uint8_t>>;

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // Camera frames (sweeps and key frames) in replay order (timestamp, then camera order).
  virtual const std::vector<dataset::CameraFrameRecord>& frames() const = 0;
  // The encoded image as stored. kNotFound / kIoError naming the file when it cannot be read.
  virtual Result<ImageBytes> read_image(const dataset::CameraFrameRecord& frame) = 0;
  // Key-frame sample timestamps (us) by sample token, when known; else boundaries use the earliest
  // key-frame timestamp of the sample.
  virtual std::map<std::string, std::int64_t> sample_timestamps_us() const { return {}; }
};

// nuScenes on disk through dataset::NuScenesReader.
class NuScenesFrameSource final : public FrameSource {
 public:
  // Loads the frame list of `scenes` (empty = all). Errors name the dataroot/table/scene.
  static Result<std::unique_ptr<NuScenesFrameSource>> open(const std::string& dataroot,
                                                           const std::string& version,
                                                           const std::vector<std::string>& scenes);
  const std::vector<dataset::CameraFrameRecord>& frames() const override { return frames_; }
  Result<ImageBytes> read_image(const dataset::CameraFrameRecord& frame) override;
  std::map<std::string, std::int64_t> sample_timestamps_us() const override {
    return sample_times_;
  }

 private:
  NuScenesFrameSource(dataset::NuScenesReader reader) : reader_(std::move(reader)) {}
  dataset::NuScenesReader reader_;
  std::vector<dataset::CameraFrameRecord> frames_;
  std::map<std::string, std::int64_t> sample_times_;
};

// Frames and image bytes held in memory (tests, benchmarks). Frames whose filename has no image
// read as kNotFound, like a missing file.
class MemoryFrameSource final : public FrameSource {
 public:
  MemoryFrameSource(std::vector<dataset::CameraFrameRecord> frames,
                    std::map<std::string, ImageBytes> images)
      : frames_(std::move(frames)), images_(std::move(images)) {}
  const std::vector<dataset::CameraFrameRecord>& frames() const override { return frames_; }
  Result<ImageBytes> read_image(const dataset::CameraFrameRecord& frame) override;

 private:
  std::vector<dataset::CameraFrameRecord> frames_;
  std::map<std::string, ImageBytes> images_;
};

// The CameraFrame header of a dataset frame as every replay publishes it (player, bag convert):
// camera, encoding jpeg, size, tokens, calibration, ego pose, scene, capture stamp and frame_id.
// Seq, publisher and publish stamps are the caller's.
msgs::CameraFrame camera_frame_header(const dataset::CameraFrameRecord& frame);

}  // namespace faultline::runtime
