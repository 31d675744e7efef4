// ROS 2 -> Faultline: subscribes ROS 2 camera topics over DDS and publishes each frame as a
// CameraFrame on ZeroMQ, exactly as the v4l2_camera node does, so the injector and detectors treat
// it like any other frame source.
//
// A topic's type is found by discovery: sensor_msgs/CompressedImage (JPEG passed through undecoded;
// PNG decoded and re-encoded) or sensor_msgs/Image (bgr8, rgb8, mono8, yuv422, yuv422_yuy2, bgra8,
// rgba8, converted to BGR and JPEG-encoded at jpeg_quality, because the injector's fault engine
// works on JPEG frames: ~10 ms per 1600x900 frame). A writer of any other type on a configured
// topic is an error logged once per topic and type (counted). The CameraInfo next to each image
// topic gives K and the size; /tf_static, when some node publishes it, gives the camera's
// extrinsics (the chain from base_frame to the image's frame_id).
//
// Each frame goes out on output_prefix + the ROS topic (/ros2/front/image_raw/compressed), with
// header.frame_id and capture stamp from the ROS header. Its camera is one of the six nuScenes
// names, the only cameras the fault engine (and fault specs) know: `channels` names it, else the
// topic's namespace upper-cased when it is one
// (/cam_front/image_raw -> CAM_FRONT), else the next unused one in CAM_FRONT, CAM_FRONT_RIGHT,
// CAM_FRONT_LEFT, CAM_BACK, CAM_BACK_LEFT, CAM_BACK_RIGHT order. So one ros2_in carries at most six
// topics.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "transport/access.hpp"

namespace faultline::ros2dds {

struct InBridgeConfig {
  int domain_id = -1;
  std::string dds_config;
  std::vector<std::string> topics;
  std::string qos = "default";
  std::map<std::string, std::string> topic_qos;
  std::map<std::string, std::string> channels;
  std::map<std::string, std::string> camera_info;
  bool tf_static = true;
  std::string base_frame = "base_link";
  int jpeg_quality = 95;
  std::string endpoint = "tcp://127.0.0.1:5600";
  int hwm = 48;
  std::string output_prefix = "/ros2";
  std::map<std::string, std::string> remap;
  int max_frames = 0;
  int wait_subscribers = 0;
  int wait_timeout_ms = 10000;
  double stats_log_period_s = 5.0;
  transport::AccessConfig access;

  template <class V>
  void visit(V& v) {
    v("domain_id", domain_id, "DDS domain; -1 = $ROS_DOMAIN_ID, else 0");
    v("dds_config", dds_config,
      "Cyclone DDS XML; empty = $CYCLONEDDS_URI, as under rmw_cyclonedds");
    v("topics", topics, "ROS 2 image topics (CompressedImage or Image, found by discovery)");
    v("qos", qos,
      "QoS of the image and CameraInfo subscriptions: "
      "default | sensor_data | reliable|best_effort,<depth>");
    v("topic_qos", topic_qos, "per-topic QoS (ROS topic -> spec)");
    v("channels", channels,
      "nuScenes camera name per image topic, e.g. CAM_FRONT (default: in topic order)");
    v("camera_info", camera_info,
      "CameraInfo topic per image topic (\"\" = none; default <ns>/camera_info)");
    v("tf_static", tf_static, "read /tf_static for the cameras' extrinsics");
    v("base_frame", base_frame, "frame the extrinsics are expressed in (camera -> base_frame)");
    v("jpeg_quality", jpeg_quality, "JPEG quality for raw Image input (1..100)");
    v("endpoint", endpoint, "ZeroMQ PUB bind address");
    v("hwm", hwm, "send queue per subscriber (messages)");
    v("output_prefix", output_prefix, "Faultline topic = prefix + ROS topic");
    v("remap", remap, "Faultline topic remaps from -> to");
    v("max_frames", max_frames, "stop after this many frames in total; 0 = until SIGINT");
    v("wait_subscribers", wait_subscribers,
      "ZeroMQ subscribers to wait for before subscribing to ROS 2");
    v("wait_timeout_ms", wait_timeout_ms, "how long to wait for them (ms)");
    v("stats_log_period_s", stats_log_period_s, "counts log period (s)");
    access.visit(v);
  }
  void validate() const;  // throws ConfigError naming the key and value
};

// Counters, written by the bridge's thread; safe to read from any thread while it runs.
struct InBridgeCounts {
  std::atomic<std::uint64_t> frames_in = 0;   // image samples taken from DDS
  std::atomic<std::uint64_t> frames_out = 0;  // CameraFrames sent
  std::atomic<std::uint64_t> bad_images =
      0;  // undecodable / unsupported encoding / wrong size: dropped
  std::atomic<std::uint64_t> camera_infos = 0;
  std::atomic<std::uint64_t> tf_static = 0;  // transforms received
  std::atomic<std::uint64_t> type_mismatch =
      0;  // writers of a non-image type on a configured topic
  std::atomic<std::uint64_t> incompatible_qos =
      0;  // QoS mismatches DDS reported (per match attempt; sum)
  // Image samples lost before this node took them: replaced in a reader's keep-last history (it
  // fell behind by more than the topic's depth), or never received (DDS SAMPLE_LOST: gaps in a
  // best-effort stream).
  std::atomic<std::uint64_t> history_replaced = 0;
  std::atomic<std::uint64_t> dds_lost = 0;
};

// The camera name of each of config.topics, in order (rule above). Throws ConfigError naming the
// topic for an unknown or repeated name, or a seventh topic.
std::vector<std::string> assign_cameras(const InBridgeConfig& config);

// The Faultline topic of a ROS image topic: prefix + topic, then remapped.
std::string faultline_topic(const InBridgeConfig& config, const std::string& ros_topic);

class InBridge {
 public:
  // Creates the DDS participant and binds the ZeroMQ output now (ConfigError on failure). `clock`
  // stamps the frames and times the counts log; it must outlive the bridge. The first form uses
  // the system clock.
  InBridge(InBridgeConfig config, std::string node, std::shared_ptr<spdlog::logger> log);
  InBridge(InBridgeConfig config, std::string node, std::shared_ptr<spdlog::logger> log,
           Clock& clock);
  ~InBridge();
  std::string endpoint() const;
  // CURVE clients refused by access.curve_allowed_clients_file (each logged); safe from any thread.
  std::uint64_t auth_refused() const;
  // Runs until `stop` or max_frames (0), or a fatal error (1).
  int run(const std::atomic<bool>& stop);
  const InBridgeCounts& counts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace faultline::ros2dds
