// The fault injector: subscribes to camera topics, asks a FramePolicy what to do with each frame
// and republishes on the faulted namespace (/faulty/cam_front/image_rect_compressed for JPEG
// passthrough, /faulty/cam_front/image_raw when decoding to bgr8). /sync/sample boundaries and the
// /sync/end stream end are forwarded in order on the same socket; every source frame also yields a
// FaultEvent on /faultline/faults, including frames dropped on purpose or because their JPEG did
// not decode. Output is numbered with the injector's own seq per topic; source_seq is kept. Cost:
// decoding a 1600x900 JPEG is ~10 ms of CPU. Decode, faults and re-encode run on `workers` threads
// (InjectorPipeline): the output keeps the input's order and is byte-identical for any worker
// count; `queue_frames` bounds what is in flight, and when it is full the receive waits, so the
// input queue (input_hwm) fills and upstream losses show up as transport_drops (seq gaps).
#pragma once

#include <spdlog/logger.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "runtime/frame_policy.hpp"
#include "runtime/remap.hpp"
#include "stats/topic_stats.hpp"
#include "transport/access.hpp"
#include "transport/publisher.hpp"
#include "transport/shm_ring.hpp"

namespace faultline::runtime {

struct InjectorConfig {
  std::vector<std::string> input_endpoints{"tcp://127.0.0.1:5600"};
  std::vector<std::string> input_topics{"/cam_", "/sync/sample"};
  int input_hwm = 8;
  bool latest_only = false;
  std::string output_endpoint = "tcp://127.0.0.1:5601";
  int output_hwm = 8;
  std::string output_prefix = "/faulty";
  bool decode = false;
  std::string sync_topic = "/sync/sample";
  std::string end_topic = "/sync/end";
  std::string faults_topic = "/faultline/faults";
  int wait_subscribers = 0;
  int wait_timeout_ms = 10000;
  bool exit_on_last = true;
  int linger_ms = 1000;
  std::int64_t max_msg_bytes = transport::kDefaultMaxMessageBytes;
  double stats_window_s = 1.0;
  double stats_log_period_s = 5.0;
  std::map<std::string, std::string> remap;
  YAML::Node faults;
  std::string corruption;
  std::uint64_t seed = 0;
  int jpeg_quality = 95;
  int workers = 0;
  int queue_frames = 0;
  bool output_shm = false;
  std::string output_shm_dir = "/dev/shm";
  int shm_slots = 32;
  std::int64_t shm_slot_bytes = static_cast<std::int64_t>(transport::kShmDefaultSlotBytes);
  transport::AccessConfig access;

  template <class V>
  void visit(V& v) {
    v("input_endpoints", input_endpoints, "publishers to subscribe to");
    v("input_topics", input_topics, "topic prefixes to subscribe to");
    v("input_hwm", input_hwm, "receive queue (messages); ~64 in lockstep");
    v("latest_only", latest_only, "keep only the newest queued frame per camera");
    v("output_endpoint", output_endpoint, "PUB bind address");
    v("output_hwm", output_hwm, "send queue per subscriber (messages)");
    v("output_prefix", output_prefix, "namespace of the faulted topics: prefix + input topic");
    v("decode", decode, "publish decoded bgr8 instead of the JPEG");
    v("sync_topic", sync_topic, "SampleBoundary topic (forwarded under the same name)");
    v("end_topic", end_topic,
      "StreamEnd topic (end of the source's run; forwarded, always subscribed)");
    v("faults_topic", faults_topic, "FaultEvent topic (one per source frame)");
    v("wait_subscribers", wait_subscribers, "subscribers of sync_topic to wait for");
    v("wait_timeout_ms", wait_timeout_ms,
      "how long to wait for them before subscribing upstream (ms)");
    v("exit_on_last", exit_on_last,
      "stop at the end of the run (StreamEnd, or last_in_run from sources without one)");
    v("linger_ms", linger_ms, "end of run: time to deliver queued messages (ms)");
    v("max_msg_bytes", max_msg_bytes,
      "largest accepted input frame (bytes; ZMQ_MAXMSGSIZE); -1 = no limit");
    v("stats_window_s", stats_window_s, "statistics window (s)");
    v("stats_log_period_s", stats_log_period_s, "info log period of statistics (s)");
    v("remap", remap, "topic remaps from -> to, applied to the outputs");
    v("faults", faults,
      "fault schedule (policy/fault_spec.hpp): a list of faults, their keys listed below; "
      "none by default");
    v("corruption", corruption, "shorthand for one fault on all cameras, e.g. fog/mid");
    v("seed", seed, "run seed of the fault draws");
    v("jpeg_quality", jpeg_quality,
      "JPEG quality of faulted frames re-encoded in JPEG mode, 1..100 (nuScenes-C: 95)");
    v("workers", workers,
      "threads that decode, corrupt and re-encode frames; "
      "0 = the cores available minus one (at least 1). The output is byte-identical for any count");
    v("queue_frames", queue_frames,
      "frames in flight between receive and send (0 = 4 x workers); "
      "when full, receiving waits and the input queue (input_hwm) absorbs");
    v("output_shm", output_shm,
      "send camera frames through a shared-memory ring, local subscribers only "
      "(docs/protocol.md §16). "
      "The pixels are written once into the ring and a small descriptor goes on the socket, "
      "so local subscribers map them without a copy");
    v("output_shm_dir", output_shm_dir,
      "directory of the ring file (tmpfs; the file is removed at exit)");
    v("shm_slots", shm_slots,
      "ring slots (>= 2): a frame stays readable until this many more frames were sent; "
      "the publisher never waits");
    v("shm_slot_bytes", shm_slot_bytes,
      "largest frame a slot holds (bytes); larger frames are refused and counted");
    access.visit(v);
  }
  void validate() const;            // throws ConfigError
  static std::string help_notes();  // the keys of a `faults` entry, for --help
};

struct InjectorCounts {
  std::uint64_t frames_in = 0;
  std::uint64_t frames_out = 0;
  std::uint64_t boundaries = 0;
  std::uint64_t stream_ends = 0;
  std::uint64_t injected_drops = 0;
  std::uint64_t corrupt_jpeg = 0;
  std::uint64_t malformed = 0;
  std::uint64_t transport_drops = 0;
  std::uint64_t superseded = 0;
  std::uint64_t oversize_refused =
      0;  // output frames over max_msg_bytes (or a shm slot): refused, not sent
  std::uint64_t window_full_waits =
      0;  // receives that waited for room in queue_frames (backpressure, no loss)
  std::uint64_t discarded_at_stop = 0;  // in flight or delayed when the run was stopped: not sent
  int workers = 0;                      // worker threads used
  std::int64_t dispatch_cpu_ns = 0;     // CPU time of the receiving thread (the one calling run())
  std::int64_t worker_cpu_ns = 0;       // ... of the worker threads
  std::int64_t output_cpu_ns = 0;       // ... of the sending thread
};

// The output topic for an input camera topic: prefix + topic, with image_rect_compressed ->
// image_raw when decoding, then remapped.
std::string faulted_topic(const InjectorConfig& config, const std::string& input_topic);

class InjectorLoop {
 public:
  // Binds the output now; the input is subscribed in run() once downstream subscribers joined.
  // `clock` (the time of stamps, latencies, delays and statistics) must outlive the loop; the first
  // form uses the system clock.
  InjectorLoop(InjectorConfig config, std::string node, std::unique_ptr<FramePolicy> policy,
               std::shared_ptr<spdlog::logger> log);
  InjectorLoop(InjectorConfig config, std::string node, std::unique_ptr<FramePolicy> policy,
               std::shared_ptr<spdlog::logger> log, Clock& clock);
  ~InjectorLoop();
  std::string output_endpoint() const;
  // The shared-memory ring file of the output ("" without output_shm).
  std::string output_shm_path() const;
  // Runs until `stop` (0), the end of the run with exit_on_last (0), or a fatal socket error (1).
  // The end of the run is a forwarded StreamEnd when the last_in_run boundary announced one
  // (stream_end_follows: the sweeps after the last sample are still corrupted and forwarded), else
  // that boundary itself.
  int run(const std::atomic<bool>& stop);
  const InjectorCounts& counts() const { return counts_; }
  // Whole-run statistics per topic (inputs: hop latency; injector outputs: receive -> publish).
  std::vector<stats::TopicWindow> stats_totals() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  InjectorCounts counts_;
};

}  // namespace faultline::runtime
