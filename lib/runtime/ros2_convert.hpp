// `faultline bag convert --format ros2`: nuScenes camera frames into a rosbag2 directory
// (bag/rosbag2.hpp) that `ros2 bag play` replays into ROS 2 nodes, without a ROS 2 install. Topics
// (foxglove/nuscenes2mcap naming, the nuScenes channel names as frames and topic namespaces):
//   /CAM_FRONT/image_rect_compressed  sensor_msgs/CompressedImage  JPEG as stored, frame_id
//   CAM_FRONT /CAM_FRONT/camera_info            sensor_msgs/CameraInfo       rectified: plumb_bob,
//   d = 0, P = [K | 0] /tf_static                        tf2_msgs/TFMessage           base_link ->
//   CAM_* (calibrated_sensor), every
//                                                                  camera in one message, again
//                                                                  when a scene changes the
//                                                                  calibration; transient local
//   /tf                               tf2_msgs/TFMessage           map -> base_link (ego pose) at
//   each frame /markers/annotations              visualization_msgs/MarkerArray  ground-truth boxes
//   of each sample in map,
//                                                                  a DELETEALL marker first
// With a FramePolicy (the injector's fault engine, as in the Foxglove convert):
//   /faulty/CAM_*/image_rect_compressed, /faulty/CAM_*/camera_info  the frames as the injector
//   forwards them
//       (dropped frames absent, delayed ones logged late with their capture stamp); with
//       clean_frames = false they take the plain camera topics instead, so the bag plays straight
//       into a stack
//   /faultline/faults                 diagnostic_msgs/DiagnosticArray  one per source frame: what
//   was injected
// Times are dataset times: header stamps and log times are the capture stamps (nuScenes us -> ns),
// so the same dataset and configuration give the same bytes.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bag/foxglove.hpp"
#include "bag/rosbag2.hpp"
#include "ros2/fault_report.hpp"
#include "runtime/bag_convert.hpp"
#include "runtime/frame_policy.hpp"
#include "runtime/frame_source.hpp"

namespace faultline::runtime {

struct Ros2ConvertConfig {
  std::string output = "bags/convert_ros2";  // bag directory to create (must not exist)
  std::string compression = "zstd";  // MCAP chunks: none | zstd | lz4 (JPEG chunks stay raw anyway)
  bool clean_frames = true;          // with faults: also keep the clean stream
  std::string image_qos = "reliable";  // camera topics' offered QoS: reliable | best_effort
  std::string output_prefix =
      "/faulty";  // faulted topic = prefix + camera topic (with clean_frames)
  std::string faults_topic = "/faultline/faults";
  std::string annotations_topic = "/markers/annotations";
  std::map<std::string, std::string>
      run_metadata;       // faultline.run Metadata record (dataset, scenes, faults, seed)
  void validate() const;  // throws ConfigError
};

struct Ros2ConvertCounts {
  std::uint64_t frames = 0;          // source camera frames read
  std::uint64_t missing_images = 0;  // skipped: image file unreadable
  std::uint64_t tf_static = 0;       // /tf_static messages
  std::uint64_t gt_updates = 0, gt_boxes = 0;
  std::uint64_t faulted_frames = 0;  // faulted frames written (after injected drops)
  std::uint64_t injected_drops = 0;
  std::uint64_t changed_frames = 0;  // faulted frames whose bytes differ from the source
  std::uint64_t drifted_frames = 0;  // faulted frames under calibration_drift (own TF frame)
  std::uint64_t fault_reports = 0;   // DiagnosticArray messages
  std::uint64_t messages = 0;        // messages written (all topics)
  std::uint64_t image_bytes = 0;     // source JPEG bytes read
};

class Ros2BagConverter {
 public:
  // policy: null = clean bag only. gt: boxes per sample token (may be empty: no annotations topic).
  Ros2BagConverter(Ros2ConvertConfig config, std::unique_ptr<FrameSource> source,
                   std::map<std::string, std::vector<bag::GtBox>> gt,
                   std::unique_ptr<FramePolicy> policy, std::shared_ptr<spdlog::logger> log);
  ~Ros2BagConverter();
  // Writes the bag; stops early (still finishing the bag) when `stop` turns true. Errors: the
  // directory exists or cannot be written.
  Result<Ros2ConvertCounts> run(const std::atomic<bool>& stop,
                                const ConvertProgressFn& progress = {});
  const bag::WriterStats& writer_stats() const { return writer_stats_; }
  const std::string& mcap_path() const { return mcap_path_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bag::WriterStats writer_stats_;
  std::string mcap_path_;
};

// The injector's decision for one source frame as its /faultline/faults report: name
// faultline/<channel>, hardware_id the channel, values action, source_seq, sample_data_token,
// sample_token, delay_ns (delay only), then the faults (ros2/fault_report.hpp sets the level).
ros2::FaultReport ros2_fault_report(const dataset::CameraFrameRecord& frame,
                                    std::uint64_t source_seq, const FaultDecision& decision);

}  // namespace faultline::runtime
