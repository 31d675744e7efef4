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
  std::string device = "/dev/video0";  // V4L2 device node
  std::string format = "auto";         // auto|mjpeg|yuyv|rgb24|bgr24|grey
  int width = 1600;                    // requested size (px)
  int height = 900;
  double rate_hz = 12.0;        // requested frame rate; 0 = driver default
  int buffers = 4;              // mmap streaming buffers
  std::string output = "auto";  // auto: MJPEG->jpeg, others->bgr8; raw: as captured
  std::string calibration;  // calibration YAML (K, sensor_to_ego); "" = identity extrinsics, no K
  std::string channel = "CAM_FRONT";  // channel name when the calibration file does not give one
  std::string endpoint = "tcp://127.0.0.1:5600";  // PUB bind address
  int hwm = 4;                                    // send queue per subscriber (messages)
  int poll_timeout_ms = 100;                      // dequeue wait; bounds shutdown latency
  int max_frames = 0;            // stop after this many frames; 0 = run until SIGINT
  bool wait_for_device = false;  // device missing at start: wait for a hot-plug instead of failing
  int wait_subscribers = 0;      // before capturing, wait for this many subscribers of the camera
  int wait_timeout_ms = 10000;   // ... at most this long (then start anyway)
  double stats_log_period_s = 5.0;  // info log of capture statistics every this many s

  transport::AccessConfig
      access;  // allow_remote and CURVE keys of every socket (transport/access.hpp)

  template <class V>
  void visit(V& v) {
    v("device", device, "V4L2 device node");
    v("format", format, "auto|mjpeg|yuyv|rgb24|bgr24|grey");
    v("width", width, "requested width (px)");
    v("height", height, "requested height (px)");
    v("rate_hz", rate_hz, "requested frame rate; 0 = driver default");
    v("buffers", buffers, "mmap streaming buffers");
    v("output", output, "auto (MJPEG->jpeg, else bgr8) or raw");
    v("calibration", calibration, "calibration YAML (intrinsics, sensor_to_ego)");
    v("channel", channel, "channel name, e.g. CAM_FRONT");
    v("endpoint", endpoint, "PUB bind address");
    v("hwm", hwm, "send queue per subscriber (messages)");
    v("poll_timeout_ms", poll_timeout_ms, "dequeue wait (ms)");
    v("max_frames", max_frames, "stop after this many frames; 0 = until SIGINT");
    v("wait_for_device", wait_for_device,
      "device missing at start: wait for it (hot-plug) instead of failing");
    v("wait_subscribers", wait_subscribers, "subscribers to wait for before capturing");
    v("wait_timeout_ms", wait_timeout_ms, "how long to wait for them (ms)");
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
