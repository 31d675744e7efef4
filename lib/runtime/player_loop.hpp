// The nuScenes camera player: publishes every camera frame (sweeps and key frames) of the chosen
// scenes in timestamp order as [topic][CameraFrame][JPEG bytes as stored], plus a SampleBoundary on
// /sync/sample right after the last key frame of each sample. At the end of a run (not looping, not
// stopped) the sweeps after the last sample follow its last_in_run boundary, then a StreamEnd on
// /sync/end.
//
// Pacing: real time scaled by `rate` (2 = twice as fast), or unpaced with rate 0. In lockstep the
// player waits after each boundary for the sink's SampleAck of that sample (PULL socket bound at
// ack_endpoint) before sending more frames, so a slow detector loses nothing; give every hop an HWM
// of ~64 (one sample's frames). Memory: one image at a time (the frame list of the chosen scenes is
// held in memory). Missing images are counted, logged (rate-limited) and skipped.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "runtime/frame_source.hpp"
#include "runtime/remap.hpp"
#include "stats/topic_stats.hpp"
#include "transport/access.hpp"

namespace faultline::runtime {

struct PlayerConfig {
  std::string dataroot = "data/nuscenes";
  std::string version = "v1.0-mini";
  std::vector<std::string> scenes;
  double rate = 1.0;
  bool loop = false;
  double start_offset_s = 0.0;
  std::string endpoint = "tcp://127.0.0.1:5600";
  int hwm = 8;
  std::string sync_topic = "/sync/sample";
  std::string end_topic = "/sync/end";
  bool lockstep = false;
  std::string ack_endpoint = "tcp://127.0.0.1:5603";
  int ack_timeout_ms = 30000;
  int wait_subscribers = 0;
  int wait_timeout_ms = 10000;
  int linger_ms = 1000;
  double stats_window_s = 1.0;
  double stats_log_period_s = 5.0;
  std::map<std::string, std::string> remap;
  transport::AccessConfig access;

  template <class V>
  void visit(V& v) {
    v("dataroot", dataroot, "nuScenes root directory (holds <version>/, samples/, sweeps/)");
    v("version", version, "table folder, e.g. v1.0-mini");
    v("scenes", scenes, "scene names; empty = all");
    v("rate", rate, "replay speed factor; 0 = as fast as possible");
    v("loop", loop, "start over at the end (last_in_run is then never sent)");
    v("start_offset_s", start_offset_s, "skip the first seconds of the run");
    v("endpoint", endpoint, "PUB bind address");
    v("hwm", hwm, "send queue per subscriber (messages); ~64 in lockstep");
    v("sync_topic", sync_topic, "SampleBoundary topic");
    v("end_topic", end_topic, "StreamEnd topic (sent after the run's last frame)");
    v("lockstep", lockstep, "wait for the sink's SampleAck per sample");
    v("ack_endpoint", ack_endpoint, "PULL bind address for SampleAck");
    v("ack_timeout_ms", ack_timeout_ms,
      "lockstep: give up waiting for a SampleAck after this (ms, warns); 0 = wait forever");
    v("wait_subscribers", wait_subscribers,
      "before the first frame, wait for this many subscribers of sync_topic");
    v("wait_timeout_ms", wait_timeout_ms,
      "how long to wait for them (ms), then start anyway (warns)");
    v("linger_ms", linger_ms, "end of run: time to deliver queued messages (ms)");
    v("stats_window_s", stats_window_s, "statistics window (s)");
    v("stats_log_period_s", stats_log_period_s, "info log period of statistics (s)");
    v("remap", remap, "topic remaps from -> to");
    access.visit(v);
  }
  void validate() const;  // throws ConfigError
};

// "/cam_front/image_rect_compressed" for "CAM_FRONT".
std::string camera_topic(const std::string& channel);

struct PlayerCounts {
  std::uint64_t frames_sent = 0;
  std::uint64_t boundaries_sent = 0;
  std::uint64_t missing_images = 0;
  std::uint64_t send_failures = 0;
  std::uint64_t ack_timeouts = 0;
};

class PlayerLoop {
 public:
  // `clock` paces the run, times the lockstep wait and stamps every message (publish_mono_ns and
  // the statistics windows in now_ns(), publish_stamp_ns in realtime_ns()); it must outlive the
  // loop.
  PlayerLoop(PlayerConfig config, std::string node, std::unique_ptr<FrameSource> source,
             Clock& clock, std::shared_ptr<spdlog::logger> log);
  ~PlayerLoop();
  // Endpoints actually bound (for tcp://127.0.0.1:* in tests) once the sockets exist, i.e. after
  // construction.
  std::string endpoint() const;
  std::string ack_endpoint() const;
  // Publishes until the end of the run (0), `stop` turns true (0) or a fatal socket error (1).
  int run(const std::atomic<bool>& stop);
  const PlayerCounts& counts() const { return counts_; }
  // Whole-run statistics per topic (inputs: hop latency; injector outputs: receive -> publish).
  std::vector<stats::TopicWindow> stats_totals() const;

 private:
  struct Impl;
  struct Pass;
  std::unique_ptr<Impl> impl_;
  PlayerCounts counts_;
};

}  // namespace faultline::runtime
