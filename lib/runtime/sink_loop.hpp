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
  std::string detections_endpoint = "tcp://127.0.0.1:5602";  // PULL bind address for detectors
  std::string detections_topic = "/detections";              // DetectionArray topic
  int detections_hwm = 1000;                                 // receive queue (messages)
  std::vector<std::string> sync_endpoints{
      "tcp://127.0.0.1:5601"};              // SampleBoundary publishers; [] = none
  std::string sync_topic = "/sync/sample";  // SampleBoundary topic
  std::string output = "results.json";      // nuScenes results JSON
  std::string journal;                      // JSON-lines journal; "" = <output>.journal
  bool resume =
      true;  // continue the journal of the same run (see `run`); false = discard any journal
  bool lockstep = false;                              // ack each collected sample to the player
  std::string ack_endpoint = "tcp://127.0.0.1:5603";  // player's ack PULL address (lockstep)
  bool exit_on_last = true;                           // exit after finalizing on last_in_run
  int finalize_grace_ms = 5000;             // after last_in_run, wait this long for detections
  std::map<std::string, std::string> meta;  // extra keys for the results' "meta"
  // The scorer's token rule: with a dataroot, only the samples of `eval_set` (as `faultline score
  // --eval_set`) are accepted; other tokens are refused and counted. "" = any token is accepted.
  std::string dataroot;                   // nuScenes root for the split; "" = off
  std::string version = "v1.0-trainval";  // dataset version under dataroot
  std::string eval_set = "val";           // split scored later (or splits.json key)
  // The run's identity, e.g. {dataset, split, injector, seed, detector}: the first journal line and
  // results meta "faultline_run". resume continues only a journal of the same identity and refuses
  // (exit 2, naming both) any other, a journal without identity included when this one is set.
  std::map<std::string, std::string> run;
  double stats_window_s = 1.0;               // statistics window (s)
  double stats_log_period_s = 5.0;           // info log of statistics every this many s
  std::map<std::string, std::string> remap;  // topic remaps (from -> to)

  transport::AccessConfig
      access;  // allow_remote and CURVE keys of every socket (transport/access.hpp)

  template <class V>
  void visit(V& v) {
    v("detections_endpoint", detections_endpoint, "PULL bind address for detectors");
    v("detections_topic", detections_topic, "DetectionArray topic");
    v("detections_hwm", detections_hwm, "receive queue (messages)");
    v("sync_endpoints", sync_endpoints, "SampleBoundary publishers to subscribe to");
    v("sync_topic", sync_topic, "SampleBoundary topic");
    v("output", output, "nuScenes results JSON path");
    v("journal", journal, "journal path; empty = <output>.journal");
    v("resume", resume, "continue a journal of the same run; false = discard any journal");
    v("lockstep", lockstep, "ack each collected sample to the player");
    v("ack_endpoint", ack_endpoint, "player's ack address");
    v("exit_on_last", exit_on_last, "exit after the last sample");
    v("finalize_grace_ms", finalize_grace_ms, "wait for detections after last_in_run (ms)");
    v("meta", meta, "extra keys for the results meta");
    v("dataroot", dataroot, "nuScenes root: refuse tokens outside eval_set; empty = accept any");
    v("version", version, "dataset version under dataroot");
    v("eval_set", eval_set, "split whose samples are the valid tokens");
    v("run", run,
      "the run's identity (dataset, split, injector, seed, detector); resume checks it");
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
