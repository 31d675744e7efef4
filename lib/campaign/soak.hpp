// `faultline soak`: the pipeline in real time for a long while, watched. Player (rate 1.0, looping,
// no lockstep) -> injector (a corruption and/or a fault schedule) -> detector run as launched
// processes (launch/soak.yaml, campaign/pipeline.hpp); the soak process itself is the sink. It
// listens to the player's and the injector's /statistics and sample boundaries (small messages, no
// images) and pulls the detections, and reports per period: frames in and out per camera,
// unintended drops, end-to-end latency (player's sample boundary -> detections received), detector
// output rate, track continuity, resident memory of every node, and the NDS of every completed loop
// over the scenes.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "campaign/progress.hpp"
#include "common/status.hpp"

namespace faultline::campaign {

struct SoakOptions {
  std::string out_dir;  // soak.json, periods.csv, loops/, params/, nodes.log
  std::string dataroot;
  std::string version = "v1.0-mini";
  std::string eval_set = "mini_val";  // split each loop is scored on
  std::vector<std::string> scenes;    // replayed scenes; empty = all
  double duration_s = 1800;
  double period_s = 60;    // one report row per period
  double rate = 1.0;       // player rate factor
  std::string corruption;  // injector corruption "fog/mid"; "" = none
  std::string
      injector_params_file;  // extra injector parameters (e.g. a `faults:` schedule), --params
  std::string detector_cmd;  // external detector (sh -c) instead of Faultline's
  std::vector<std::string> detector_params;  // key:=value for Faultline's detector
  std::string bin_dir;                       // node executables
  std::string pipeline_file;  // the nodes (a launch file); "" = launch/soak.yaml built in
  std::uint64_t seed = 1;
};

struct NodeMemory {
  std::string node;
  int pid = 0;
  double rss_mb = 0;
};

struct SoakPeriod {
  int index = 0;                                    // 1-based
  double end_s = 0;                                 // since start
  std::map<std::string, std::uint64_t> frames_in;   // per camera topic: published by the player
  std::map<std::string, std::uint64_t> frames_out;  // per camera topic: forwarded by the injector
  std::uint64_t transport_drops = 0;                // seq gaps seen by the injector (unintended)
  std::uint64_t superseded = 0;                     // skipped by a latest-only policy
  std::uint64_t injected_drops = 0;                 // dropped on purpose by the fault schedule
  std::uint64_t samples_published = 0;
  std::uint64_t detection_arrays = 0;
  std::uint64_t malformed = 0;  // undecodable messages the soak received
  double latency_ms_p50 = 0,
         latency_ms_p99 = 0;  // sample boundary published -> detections received
  double continuity = -1;  // -1: not measurable (no two consecutive samples detected). Detections
                           // continuing a detection of the previous sample (same class, near)
  std::vector<NodeMemory> memory;
};

struct SoakLoop {
  int index = 0;  // 1-based
  std::size_t samples = 0, samples_with_detections = 0;
  bool scored = false;
  double nds = 0, map = 0;
  std::string error;
};

struct SoakResult {
  std::vector<SoakPeriod> periods;
  std::vector<SoakLoop> loops;
  std::vector<std::string> node_failures;  // nodes that exited on their own or crashed
  double rss_growth_mb = 0;  // max over nodes: last period's RSS - second period's RSS
  std::string summary_path;
};

// Runs until `duration_s` elapses or `stop` is set; each period's and loop's row goes to `progress`
// as it completes (from the calling thread) and to out_dir. Fails only on setup errors (missing
// executable, unwritable folder).
Result<SoakResult> run_soak(const SoakOptions& opts, const std::atomic<bool>& stop,
                            const ProgressLine& progress);

// Share of `current` boxes (x, y, class) that continue one of `previous` (same class, within
// `radius_m`).
struct TrackPoint {
  double x = 0, y = 0;
  std::string cls;
};
double track_continuity(const std::vector<TrackPoint>& previous,
                        const std::vector<TrackPoint>& current, double radius_m = 2.5);

// Resident set size of a process in MB from /proc/<pid>/status (VmRSS); -1 when unreadable.
double process_rss_mb(int pid);

// Direct children of `parent` (from /proc/*/stat), with their command names.
std::vector<NodeMemory> child_processes(int parent);

}  // namespace faultline::campaign
