// `faultline bag convert`: nuScenes camera frames straight into an MCAP bag, without sockets or
// real-time pacing. The bag holds what a live recording of player (-> injector) would hold
// (bag_layout.hpp), so `bag play` republishes it:
//   - replay channels: every camera frame as the player publishes it ([topic][CameraFrame][JPEG as
//     stored], seq per topic from 1) and /sync/sample boundaries after each sample's last key
//     frame;
//   - the Foxglove view (nuscenes2mcap naming): CompressedImage per camera, CameraCalibration,
//     /tf (map -> base_link from the frame's ego pose, base_link -> cam_x from calibrated_sensor)
//     and /markers/annotations (SceneUpdate of the sample's ground-truth boxes, at the sample
//     time);
//   - with a FramePolicy (faults baked in, the injector's code): /faulty/... frames as the injector
//     would forward them (FaultState filled, injector seq, source_seq kept; dropped frames absent),
//     their Foxglove view, and one FaultEvent per source frame on /faultline/faults.
// Times are dataset times: log_time = publish_time = capture stamp (nuScenes us x 1000), so the
// same dataset and configuration give the same bytes. Scenes keep their own (far apart) times.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "bag/foxglove.hpp"
#include "bag/writer.hpp"
#include "runtime/frame_policy.hpp"
#include "runtime/frame_source.hpp"

namespace faultline::runtime {

struct ConvertConfig {
  std::string output = "bags/convert.mcap";  // bag path
  std::string compression = "zstd";       // none | zstd | lz4 (JPEG chunks are stored raw anyway)
  bool foxglove_view = true;              // CompressedImage, calibration, /tf, markers
  bool clean_frames = true;               // with faults: also keep the clean stream
  std::string publisher = "bag_convert";  // header.publisher of frames and boundaries
  std::string injector_publisher =
      "fault_injector";                   // header.publisher of faulted frames and events
  std::string output_prefix = "/faulty";  // faulted topic = prefix + camera topic
  std::string sync_topic = "/sync/sample";
  std::string faults_topic = "/faultline/faults";
  std::map<std::string, std::string>
      run_metadata;       // extra faultline.run entries (dataset, scenes, faults)
  void validate() const;  // throws ConfigError
};

struct ConvertCounts {
  std::uint64_t frames = 0;          // camera frames written (clean stream)
  std::uint64_t missing_images = 0;  // skipped: image file unreadable
  std::uint64_t boundaries = 0;
  std::uint64_t gt_updates = 0, gt_boxes = 0;
  std::uint64_t faulted_frames = 0;  // frames on /faulty/... (after injected drops)
  std::uint64_t injected_drops = 0;
  std::uint64_t changed_frames = 0;  // faulted frames whose bytes differ from the source
  std::uint64_t messages = 0;        // MCAP messages written (all channels)
  std::uint64_t image_bytes = 0;     // source JPEG bytes read
};

// Ground-truth boxes by sample token, for the samples in `sample_tokens` (all when empty): every
// sample_annotation with its instance's category. Missing/invalid tables -> Status naming the file.
Result<std::map<std::string, std::vector<bag::GtBox>>> load_gt_boxes(
    const std::string& dataroot, const std::string& version,
    const std::set<std::string>& sample_tokens);

// The player's CameraFrame header (camera_frame_header) with dataset-time publish stamps: what a
// converted frame carries and what the fault policy sees.
msgs::CameraFrame convert_frame_header(const dataset::CameraFrameRecord& f, std::uint64_t seq,
                                       const std::string& publisher, std::size_t payload_bytes);

// done / total camera frames; called every few frames and once at the end.
using ConvertProgressFn = std::function<void(std::uint64_t done, std::uint64_t total)>;

class BagConverter {
 public:
  // policy: null = clean bag only. gt: boxes per sample token (may be empty).
  BagConverter(ConvertConfig config, std::unique_ptr<FrameSource> source,
               std::map<std::string, std::vector<bag::GtBox>> gt,
               std::unique_ptr<FramePolicy> policy, std::shared_ptr<spdlog::logger> log);
  ~BagConverter();
  // Writes the bag; stops early (still finalising the file) when `stop` turns true.
  // Errors: the bag cannot be opened or written.
  Result<ConvertCounts> run(const std::atomic<bool>& stop, const ConvertProgressFn& progress = {});
  const bag::WriterStats& writer_stats() const { return writer_stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bag::WriterStats writer_stats_;
};

}  // namespace faultline::runtime
