// The detector node's loop: subscribes to the faulted camera topics (jpeg or bgr8) and the sample
// boundaries, runs the reference detector and PUSHes one DetectionArray per key-frame sample to the
// sink.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "transport/access.hpp"

namespace faultline::detector {

struct DetectorLoopConfig {
  std::vector<std::string> input_endpoints{"tcp://127.0.0.1:5601"};
  std::string input_prefix = "/faulty/";
  std::string sync_topic = "/sync/sample";
  int input_hwm = 64;
  std::string sink_endpoint = "tcp://127.0.0.1:5602";
  std::string detections_topic = "/detections";
  double scale = 1.0;
  bool temporal = true;
  bool normalise = true;
  bool exit_on_last = true;
  int linger_ms = 2000;
  transport::AccessConfig access;

  template <class V>
  void visit(V& v) {
    v("input_endpoints", input_endpoints, "camera publishers to subscribe to (the injector's PUB)");
    v("input_prefix", input_prefix, "prefix of the camera topics to subscribe to");
    v("sync_topic", sync_topic, "SampleBoundary topic");
    v("input_hwm", input_hwm, "receive queue (messages)");
    v("sink_endpoint", sink_endpoint,
      "detection sink PULL address (the detector connects and PUSHes)");
    v("detections_topic", detections_topic, "DetectionArray topic");
    v("scale", scale, "input scale 1.0, 0.5 or 0.25");
    v("temporal", temporal, "track over every frame (true) or single key frame (false)");
    v("normalise", normalise,
      "exposure and contrast normalisation before segmentation (docs/detector.md)");
    v("exit_on_last", exit_on_last, "stop after the last_in_run boundary");
    v("linger_ms", linger_ms, "end of run: time to deliver queued detections (ms)");
    access.visit(v);
  }
  void validate() const;  // throws ConfigError
};

struct DetectorLoopCounts {
  std::uint64_t frames = 0, malformed = 0, undecodable = 0, boundaries = 0, arrays_sent = 0,
                send_failures = 0;
  std::uint64_t boundaries_lost =
      0;  // seq gaps on the sync topic: samples that got no DetectionArray
  // Key frames a boundary announces (its frames_sent) that never arrived here: lost in transport,
  // dropped by an injected fault, or sent before a respawned detector connected. Their samples are
  // detected from the frames that did arrive (incomplete_samples counts those samples).
  std::uint64_t key_frames_missing = 0;
  std::uint64_t incomplete_samples = 0;
  // Samples after a break in the stream (joined mid-run, publisher restarted, boundaries lost):
  // detected without the ego-motion history of the samples before (the road curvature estimate
  // starts over).
  std::uint64_t stream_breaks = 0;
  // Shared-memory frames (the injector's output_shm) whose ring slot was reused before or while
  // they were read.
  std::uint64_t shm_overwritten = 0;
};

class DetectorLoop {
 public:
  // Connects now, so a publisher waiting for subscribers sees this node. `clock` stamps the
  // DetectionArrays and times processing_ns; it must outlive the loop. The first form uses the
  // system clock.
  DetectorLoop(DetectorLoopConfig config, std::string node, std::shared_ptr<spdlog::logger> log);
  DetectorLoop(DetectorLoopConfig config, std::string node, std::shared_ptr<spdlog::logger> log,
               Clock& clock);
  ~DetectorLoop();
  // Runs until `stop` (0), last_in_run with exit_on_last (0) or context termination (0).
  int run(const std::atomic<bool>& stop);
  const DetectorLoopCounts& counts() const { return counts_; }
  // Handshakes the sink refused (its CURVE allowed-clients list): why sends may have failed.
  std::uint64_t refused_by_peer();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  DetectorLoopCounts counts_;
};

}  // namespace faultline::detector
