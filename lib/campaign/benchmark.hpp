// `faultline benchmark`: the RoboBEV matrix run live through launched nodes. For each condition
// (clean, corruption x level, x seed) it starts sink, injector, detector and player as processes in
// lockstep (nothing lost however slow the detector), scores the collected results with the official
// metric, then computes mCE/mRR against a baseline and writes the tables and the HTML report.
#pragma once

#include <array>
#include <atomic>
#include <cstdio>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "launch/supervisor.hpp"
#include "scoring/robustness.hpp"

namespace faultline::campaign {

struct BenchmarkOptions {
  std::string out_dir;   // DIR: runs/, summary.json, robustness.*, report.html
  std::string dataroot;  // nuScenes tree (synthetic by default, see cmd_benchmark)
  std::string version = "v1.0-mini";
  std::string eval_set = "mini_val";     // split scored (predefined or splits.json key)
  std::vector<std::string> scenes;       // replayed scenes; empty = all
  std::vector<std::string> corruptions;  // RoboBEV names (camera_crash, ..., low_light, fog, snow)
  std::vector<std::string> levels{"easy", "mid", "hard"};
  int seeds = 1;             // faulted runs repeated with seeds 1..N
  std::string detector_cmd;  // external detector command line (sh -c); "" = our detector
  std::vector<std::string> detector_params;  // key:=value for our detector node
  std::string baseline_manifest;             // "" = the paper's DETR3D
  std::string bin_dir;                       // where the node executables are
  std::string corrupt_bench;  // bench/results/corrupt.json for the report, if present
  int run_timeout_s = 600;    // a run that takes longer is stopped and marked failed
  // Faultline's detector only: also run it at input scales 0.5 and 0.25 (clean) and single-frame
  // (clean, frame_lost, camera_crash), for the report's NDS-vs-fps and temporal-vs-single-frame
  // views.
  bool variants = true;
};

struct ConditionResult {
  std::string variant;    // "" = the configured detector; else e.g. "single-frame, scale 1"
  std::string condition;  // "clean", "fog/mid"
  int seed = 0;
  bool ok = false;
  std::string error;
  double nds = 0, map = 0;
  std::array<double, 5> tp_errors{};  // mATE, mASE, mAOE, mAVE, mAAE
  double wall_s = 0;
  double detector_ms_per_sample = -1;  // detector compute per sample (from the sink's results meta)
};

struct BenchmarkResult {
  std::vector<ConditionResult> runs;
  bool robustness_ok = false;
  std::string robustness_error;  // why mCE/mRR were not computed although corruptions were asked for
  scoring::RobustnessSummary robustness;
  std::string report_path;
};

// Runs the whole matrix; progress lines go to `log`. Fails only on setup problems (a missing node
// executable, an unwritable output dir); a failing run is recorded and the matrix continues.
Result<BenchmarkResult> run_benchmark(const BenchmarkOptions& opts, const std::atomic<bool>& stop,
                                      std::FILE* log);

// One node process: `<bin_dir>/<name> --name <name> -p k:=v ...`.
launch::ChildSpec node_child(const std::string& bin_dir, const std::string& name,
                             std::vector<std::string> params, bool required);

// The injector's corruption name for a RoboBEV name (low_light -> dark).
std::string injector_corruption_name(const std::string& robobev_name);

}  // namespace faultline::campaign
