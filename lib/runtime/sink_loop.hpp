// The detection sink: collects DetectionArrays on a PULL socket (lossless), journals each sample as
// it arrives and writes the nuScenes results JSON atomically on last_in_run (after the detections
// of every announced sample arrived, or a grace period) and on exit. It also subscribes to
// /sync/sample so samples without detections still get an empty list. In lockstep it acks each
// collected sample to the player (PUSH to ack_endpoint). Nothing collected is lost on
// SIGINT/SIGTERM or when another node crashes; a restarted sink recovers from the journal.
#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "runtime/remap.hpp"
#include "stats/topic_stats.hpp"
#include "transport/access.hpp"

namespace faultline::runtime {

struct SinkConfig {
  std::string detections_endpoint = "tcp://127.0.0.1:5602";
  std::string detections_topic = "/detections";
  int detections_hwm = 1000;
  std::vector<std::string> sync_endpoints{"tcp://127.0.0.1:5601"};
  std::string sync_topic = "/sync/sample";
  std::string output = "results.json";
  std::string journal;
  bool resume = true;
  bool lockstep = false;
  std::string ack_endpoint = "tcp://127.0.0.1:5603";
  bool exit_on_last = true;
  int finalize_grace_ms = 5000;
  std::map<std::string, std::string> meta;
  std::string dataroot;
  std::string version = "v1.0-trainval";
  std::string eval_set = "val";
  std::map<std::string, std::string> run;
  double stats_window_s = 1.0;
  double stats_log_period_s = 5.0;
  std::map<std::string, std::string> remap;
  transport::AccessConfig access;

  template <class V>
  void visit(V& v) {
    v("detections_endpoint", detections_endpoint, "PULL bind address for detectors");
    v("detections_topic", detections_topic, "DetectionArray topic");
    v("detections_hwm", detections_hwm, "receive queue (messages)");
    v("sync_endpoints", sync_endpoints, "SampleBoundary publishers to subscribe to; [] = none");
    v("sync_topic", sync_topic, "SampleBoundary topic");
    v("output", output, "nuScenes results JSON path");
    v("journal", journal, "journal path; empty = <output>.journal");
    v("resume", resume, "continue a journal of the same run; false = discard any journal");
    v("lockstep", lockstep, "ack each collected sample to the player");
    v("ack_endpoint", ack_endpoint, "player's SampleAck PULL address (lockstep)");
    v("exit_on_last", exit_on_last, "exit after finalizing on last_in_run");
    v("finalize_grace_ms", finalize_grace_ms,
      "after last_in_run, wait this long for missing detections (ms)");
    v("meta", meta, "extra keys for the results meta");
    v("dataroot", dataroot,
      "nuScenes root: accept only the samples of eval_set, as `faultline score --eval_set` does, "
      "and refuse and count other tokens; empty = accept any");
    v("version", version, "dataset version under dataroot");
    v("eval_set", eval_set, "split whose samples are the valid tokens (or a splits.json key)");
    v("run", run,
      "the run's identity (dataset, split, injector, seed, detector), "
      "the journal's first line and the results meta faultline_run. "
      "resume continues only a journal of the same identity and refuses any other (exit 2), "
      "one without identity too when this is set");
    v("stats_window_s", stats_window_s, "statistics window (s)");
    v("stats_log_period_s", stats_log_period_s, "info log period of statistics (s)");
    v("remap", remap, "topic remaps from -> to");
    access.visit(v);
  }
  void validate() const;  // throws ConfigError
};

struct SinkCounts {
  std::uint64_t detection_arrays = 0;
  std::uint64_t boxes = 0;
  std::uint64_t boundaries = 0;
  std::uint64_t acks_sent = 0;
  std::uint64_t ack_send_failures = 0;  // lockstep acks not sent (logged with the cause)
  std::uint64_t malformed = 0;
  std::uint64_t recovered_lines = 0;
  std::uint64_t rejected_boxes = 0;   // refused by the scorer's rules (the rest of the array kept)
  std::uint64_t rejected_arrays = 0;  // refused whole: no sample_token, or over 500 boxes
  std::uint64_t rejected_boundaries = 0;  // boundaries naming a sample outside the split (dataroot)
  std::uint64_t bad_journal_lines = 0;    // journal lines that could not be read back on resume
  std::uint64_t duplicate_arrays =
      0;  // a second array for a sample (a restarted source): the last kept
  std::uint64_t unanswered_samples =
      0;  // at finalize: announced samples without detections (empty lists)
};

class SinkLoop {
 public:
  // `clock` times the finalize grace and the statistics windows and stamps the acks; it must
  // outlive the loop. The first form uses the system clock.
  SinkLoop(SinkConfig config, std::string node, std::shared_ptr<spdlog::logger> log);
  SinkLoop(SinkConfig config, std::string node, std::shared_ptr<spdlog::logger> log, Clock& clock);
  ~SinkLoop();
  std::string detections_endpoint() const;  // as bound
  // Runs until `stop` (finalize, 0), a completed run with exit_on_last (0) or a fatal error (1).
  int run(const std::atomic<bool>& stop);
  const SinkCounts& counts() const { return counts_; }
  // Whole-run statistics per topic (inputs: hop latency; injector outputs: receive -> publish).
  std::vector<stats::TopicWindow> stats_totals() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  SinkCounts counts_;
};

}  // namespace faultline::runtime
