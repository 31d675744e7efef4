// Faultline -> ROS 2: subscribes the injector's faulted CameraFrames (and FaultEvents) on ZeroMQ
// and publishes them as ROS 2 topics over DDS, so a ROS 2 stack, RViz or Foxglove sees the faulted
// stream live.
//
// Per camera topic: sensor_msgs/CompressedImage (JPEG bytes as the injector sent them; raw frames
// encoded at jpeg_quality) or sensor_msgs/Image bgr8 (JPEG decoded: ~10 ms per 1600x900 frame),
// plus sensor_msgs/CameraInfo from the frame's K (plumb_bob, zero distortion, P = [K|0]: nuScenes
// images are rectified). Every FaultEvent becomes a diagnostic_msgs/DiagnosticArray. With
// publish_tf, each camera's sensor_to_ego goes to /tf_static (base_frame -> frame_id, transient
// local) and each frame's ego pose to /tf (map_frame -> base_frame).
//
// Topic names: the Faultline topic without strip_prefix, plus topic_suffix, then remapped:
// /faulty/cam_front/image_rect_compressed -> /cam_front/image_rect_compressed (replay; with names =
// nuscenes /CAM_FRONT/image_rect_compressed, the name `bag convert --format ros2` writes), or with
// strip_prefix /faulty/ros2 and topic_suffix /faulty: /faulty/ros2/front/image ->
// /front/image/faulty (proxy). The CameraInfo topic is the image_transport sibling of the
// unsuffixed name, plus the suffix: /front/camera_info/faulty. A topic's writers are created at its
// first frame, or at start for the topics listed in `advertise`, so that ROS 2 subscribers discover
// them (and match, ~0.1-1 s) before frames flow: a volatile reader gets no sample written before it
// matched.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "transport/access.hpp"

namespace faultline::ros2dds {

struct OutBridgeConfig {
  int domain_id = -1;
  std::string dds_config;
  std::vector<std::string> input_endpoints{"tcp://127.0.0.1:5601"};
  std::vector<std::string> input_topics{"/faulty/"};
  std::vector<std::string> advertise;
  int input_hwm = 48;
  std::string strip_prefix = "/faulty";
  std::string topic_suffix;
  std::map<std::string, std::string> remap;
  std::string names = "as_is";
  std::string output = "compressed";
  int jpeg_quality = 95;
  std::string qos = "default";
  std::map<std::string, std::string> topic_qos;
  bool camera_info = true;
  std::string faults_topic = "/faultline/faults";
  std::string diagnostics_topic = "/faultline/faults";
  bool publish_tf = false;
  std::string base_frame = "base_link";
  std::string map_frame = "map";
  std::string end_topic = "/sync/end";
  bool exit_on_end = true;
  int max_frames = 0;
  int wait_readers = 0;
  int wait_timeout_ms = 10000;
  double stats_log_period_s = 5.0;
  transport::AccessConfig access;

  template <class V>
  void visit(V& v) {
    v("domain_id", domain_id, "DDS domain; -1 = $ROS_DOMAIN_ID, else 0");
    v("dds_config", dds_config, "Cyclone DDS XML; empty = $CYCLONEDDS_URI");
    v("input_endpoints", input_endpoints, "ZeroMQ publishers of faulted frames (the injector)");
    v("input_topics", input_topics, "camera frame topic prefixes");
    v("input_hwm", input_hwm, "receive queue (messages)");
    v("advertise", advertise,
      "Faultline camera topics to offer on ROS 2 from the start (else at their first frame)");
    v("strip_prefix", strip_prefix, "removed from the Faultline topic to make the ROS topic");
    v("topic_suffix", topic_suffix, "appended to the ROS topic (/faulty for a proxy)");
    v("remap", remap, "ROS topic remaps from -> to, after strip_prefix and topic_suffix");
    v("names", names,
      "as_is, or nuscenes: a nuScenes camera's topics and frame_id take its channel name "
      "(/CAM_FRONT/..., CAM_FRONT) as in bag convert --format ros2 and nuscenes2mcap");
    v("output", output, "compressed (CompressedImage) or raw (Image bgr8)");
    v("jpeg_quality", jpeg_quality,
      "JPEG quality when encoding raw frames to CompressedImage (1..100; nuScenes-C used 95)");
    v("qos", qos,
      "QoS of the image, CameraInfo and diagnostics writers: "
      "default | sensor_data | reliable|best_effort,<depth>");
    v("topic_qos", topic_qos, "per-topic QoS (ROS topic after renaming -> spec)");
    v("camera_info", camera_info, "publish CameraInfo next to each image topic");
    v("faults_topic", faults_topic, "Faultline FaultEvent topic (\"\" = none)");
    v("diagnostics_topic", diagnostics_topic, "ROS topic of the DiagnosticArray");
    v("publish_tf", publish_tf, "publish /tf_static (extrinsics) and /tf (ego pose)");
    v("base_frame", base_frame, "parent frame of the cameras, child of map_frame");
    v("map_frame", map_frame, "parent frame of the ego pose");
    v("end_topic", end_topic, "StreamEnd topic of a finite run (always subscribed)");
    v("exit_on_end", exit_on_end, "stop after a StreamEnd");
    v("max_frames", max_frames, "stop after this many frames; 0 = no limit");
    v("wait_readers", wait_readers,
      "matched DDS readers to wait for before a topic's first sample");
    v("wait_timeout_ms", wait_timeout_ms,
      "how long to wait for them per topic (ms), then write anyway");
    v("stats_log_period_s", stats_log_period_s, "counts log period (s)");
    access.visit(v);
  }
  void validate() const;  // throws ConfigError naming the key and value
};

// Counters, written by the bridge's thread; safe to read from any thread while it runs.
struct OutBridgeCounts {
  std::atomic<std::uint64_t> frames_in = 0;   // CameraFrames received
  std::atomic<std::uint64_t> frames_out = 0;  // images written to DDS
  std::atomic<std::uint64_t> events = 0;      // DiagnosticArrays written
  std::atomic<std::uint64_t> malformed =
      0;  // unparsable messages or undecodable JPEG (raw output): dropped
  std::atomic<std::uint64_t> transport_drops = 0;  // seq gaps on the ZeroMQ input
  std::atomic<std::uint64_t> write_failures = 0;   // DDS writes that failed (frame lost)
  std::atomic<std::uint64_t> incompatible_qos =
      0;  // QoS mismatches DDS reported (per match attempt; sum)
};

// The ROS topic of a Faultline camera topic (rule above); "" when it does not start with
// strip_prefix + "/". With names = nuscenes, a first topic segment that is a nuScenes camera in
// lower case becomes its channel name.
std::string ros_topic_for(const OutBridgeConfig& config, const std::string& faultline_topic);
// The CameraInfo topic of a Faultline camera topic: the image_transport sibling of the unsuffixed
// ROS topic, plus topic_suffix, then remapped; "" like ros_topic_for.
std::string ros_camera_info_topic_for(const OutBridgeConfig& config,
                                      const std::string& faultline_topic);
// The frame_id written for a Faultline frame_id: with names = nuscenes, "cam_front" -> "CAM_FRONT"
// (the /tf_static child frame too); other ids, and every id with names = as_is, unchanged.
std::string ros_frame_id_for(const OutBridgeConfig& config, const std::string& faultline_frame_id);

class OutBridge {
 public:
  // Creates the DDS participant and connects the ZeroMQ input (ConfigError on failure). `clock`
  // times the counts log; it must outlive the bridge. The first form uses the system clock.
  OutBridge(OutBridgeConfig config, std::string node, std::shared_ptr<spdlog::logger> log);
  OutBridge(OutBridgeConfig config, std::string node, std::shared_ptr<spdlog::logger> log,
            Clock& clock);
  ~OutBridge();
  // Runs until `stop` (0), a StreamEnd with exit_on_end or max_frames (0, after the readers
  // acknowledged), or a fatal socket error (1).
  int run(const std::atomic<bool>& stop);
  const OutBridgeCounts& counts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace faultline::ros2dds
