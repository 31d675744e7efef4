// The v4l2_camera node's loop: captures from one V4L2 device and publishes CameraFrames like the
// nuScenes player (topic /<channel>/image_rect_compressed for JPEG, /<channel>/image_raw for raw),
// with the calibration from a YAML file, so injector, detector and sink treat it like a nuScenes
// camera. Several cameras run as several nodes in one launch file.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "common/clock.hpp"
#include "transport/access.hpp"
#include "v4l2/calibration.hpp"
#include "v4l2/capture.hpp"

namespace faultline::v4l2 {

struct CameraNodeConfig {
  std::string device = "/dev/video0";
  std::string format = "auto";
  int width = 1600;
  int height = 900;
  double rate_hz = 12.0;
  int buffers = 4;
  std::string output = "auto";
  std::string calibration;
  std::string channel = "CAM_FRONT";
  std::string endpoint = "tcp://127.0.0.1:5600";
  int hwm = 4;
  int poll_timeout_ms = 100;
  int max_frames = 0;
  bool wait_for_device = false;
  int wait_subscribers = 0;
  int wait_timeout_ms = 10000;
  double stats_log_period_s = 5.0;
  transport::AccessConfig access;

  template <class V>
  void visit(V& v) {
    v("device", device, "V4L2 device node");
    v("format", format, "auto|mjpeg|yuyv|rgb24|bgr24|grey");
    v("width", width, "requested width (px)");
    v("height", height, "requested height (px)");
    v("rate_hz", rate_hz, "requested frame rate; 0 = driver default");
    v("buffers", buffers, "mmap streaming buffers");
    v("output", output, "auto (MJPEG -> jpeg, others -> bgr8) or raw (as captured)");
    v("calibration", calibration,
      "calibration YAML (intrinsics, sensor_to_ego); empty = identity extrinsics, no intrinsics");
    v("channel", channel,
      "channel name when the calibration file does not give one, e.g. CAM_FRONT");
    v("endpoint", endpoint, "PUB bind address");
    v("hwm", hwm, "send queue per subscriber (messages)");
    v("poll_timeout_ms", poll_timeout_ms, "dequeue wait (ms); bounds the shutdown latency");
    v("max_frames", max_frames, "stop after this many frames; 0 = until SIGINT");
    v("wait_for_device", wait_for_device,
      "device missing at start: wait for it (hot-plug) instead of failing");
    v("wait_subscribers", wait_subscribers,
      "subscribers of the camera topic to wait for before capturing");
    v("wait_timeout_ms", wait_timeout_ms, "how long to wait for them (ms), then start anyway");
    v("stats_log_period_s", stats_log_period_s, "capture statistics log period (s)");
    access.visit(v);
  }
  void validate() const;  // throws ConfigError
  CaptureConfig capture() const;
};

// "/cam_front/image_rect_compressed" (jpeg) or "/cam_front/image_raw".
std::string camera_output_topic(const std::string& channel, const std::string& encoding);

// Runs until `stop`, max_frames, or a fatal device problem (returns 1; 0 on clean shutdown).
// `on_bound` receives the bound endpoint (e.g. the OS-chosen tcp port) before capture starts.
int run_camera_node(const CameraNodeConfig& cfg, const std::string& node,
                    Capture::DeviceFactory factory, Clock& clock,
                    std::shared_ptr<spdlog::logger> log, const std::atomic<bool>& stop,
                    const std::function<void(const std::string&)>& on_bound = {});

}  // namespace faultline::v4l2
