// nuScenes database reader for camera replay (<dataroot>/<version>/*.json, samples/, sweeps/),
// scene-scoped: small tables (scene, sample, sensor, calibrated_sensor, log) are loaded at open();
// the big ones (sample_data ~1.3 GB and ego_pose ~0.5 GB in trainval) are streamed per request,
// keeping only the selected scenes' records. Every table is read with nuscenes::stream_table, the
// fields listed in nuscenes/schema.hpp.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/bounded_read.hpp"
#include "common/status.hpp"

namespace faultline::dataset {

struct Pose {
  std::array<double, 3> translation{};
  std::array<double, 4> rotation{1, 0, 0, 0};  // w, x, y, z
};

struct CameraFrameRecord {  // one camera sample_data record, sweep or key frame
  std::string channel;      // "CAM_FRONT"
  std::string filename;     // relative to dataroot, e.g. "samples/CAM_FRONT/...jpg"
  std::string sample_data_token, sample_token, scene_token, scene_name;
  bool is_key_frame = false;
  std::int64_t timestamp_us = 0;
  int width = 0, height = 0;
  std::array<double, 9> intrinsics{};  // row-major K
  Pose sensor_to_ego;                  // calibrated_sensor
  Pose ego_pose;                       // ego_pose of this sample_data
};

struct SampleRecord {
  std::string token, scene_token, prev, next;
  std::int64_t timestamp_us = 0;
};

struct SceneRecord {
  std::string token, name, description, log_token, first_sample_token, last_sample_token;
  int nbr_samples = 0;
};

using ProblemFn = std::function<void(const Status&)>;  // bad records are reported, not fatal

// The six camera channels in replay order (ties on timestamp are broken by this order).
const std::array<const char*, 6>& camera_channels();

// Per-scene sample_data counts, for `faultline dataset info`.
struct SceneFrameCounts {
  std::int64_t camera_frames = 0, camera_key_frames = 0, other_frames = 0;
};

class NuScenesReader {
 public:
  // Opens <dataroot>/<version>; reads only the small tables and checks that sample_data.json and
  // ego_pose.json exist. Missing dir/table or malformed JSON -> Status naming the file (and byte
  // offset for JSON errors).
  static Result<NuScenesReader> open(const std::string& dataroot, const std::string& version);

  const std::vector<SceneRecord>& scenes() const { return scenes_; }

  // Camera frames (6 cameras, sweeps + key frames) of the named scenes (empty = all scenes), sorted
  // by (timestamp_us, channel order of camera_channels()). An unknown scene name is an error
  // listing the known ones. Streams sample_data.json then ego_pose.json; memory is proportional to
  // the selected scenes only.
  Result<std::vector<CameraFrameRecord>> load_camera_frames(
      const std::vector<std::string>& scene_names, const ProblemFn& on_problem = {}) const;

  // Key-frame samples of the named scenes (empty = all) in timestamp order.
  Result<std::vector<SampleRecord>> samples_of(const std::vector<std::string>& scene_names) const;

  // One streaming pass over sample_data.json counting frames per scene token.
  Result<std::map<std::string, SceneFrameCounts>> count_frames(
      const ProblemFn& on_problem = {}) const;

  std::string path_of(const CameraFrameRecord& f) const;   // absolute file path
  std::string table_path(const std::string& table) const;  // <dataroot>/<version>/<table>.json
  const std::string& dataroot() const { return dataroot_; }
  const std::string& version() const { return version_; }

 private:
  struct Calibration {
    std::string channel, modality;
    std::array<double, 9> intrinsics{};
    Pose sensor_to_ego;
  };
  Result<std::vector<const SceneRecord*>> resolve(
      const std::vector<std::string>& scene_names) const;
  // open()'s steps, one per small table (check_logs: every scene's log_token is in log.json).
  Status load_scenes();
  Status load_samples();
  Status load_calibrations();
  Status check_logs() const;
  // load_camera_frames' two scans: sample_data (camera frames of the selected samples, indexed by
  // ego pose token), then ego_pose (frames without a pose are reported and dropped).
  Status stream_camera_frames(
      const std::unordered_map<std::string, const SceneRecord*>& scene_of_sample,
      const ProblemFn& on_problem, std::vector<CameraFrameRecord>& frames,
      std::unordered_map<std::string, std::size_t>& frame_of_pose) const;
  Status attach_ego_poses(const std::unordered_map<std::string, std::size_t>& frame_of_pose,
                          const ProblemFn& on_problem,
                          std::vector<CameraFrameRecord>& frames) const;

  std::string dataroot_, version_;
  std::vector<SceneRecord> scenes_;
  std::vector<SampleRecord> samples_;  // table order
  std::unordered_map<std::string, std::size_t> sample_index_;
  std::unordered_map<std::string, Calibration> calibrations_;
};

// Reads a whole file (an image) into memory; missing file -> kNotFound naming the path, more than
// `max_bytes` (kMaxImageFileBytes, 1 GiB, by default) -> kInvalidArgument naming the path and the
// limit.
Result<std::vector<std::uint8_t>> read_file(const std::string& path,
                                            std::size_t max_bytes = kMaxImageFileBytes);

}  // namespace faultline::dataset
