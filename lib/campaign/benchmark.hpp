// `faultline benchmark`: the RoboBEV matrix run live through launched nodes. For each condition
// (clean, corruption x level, x seed) it starts sink, injector, detector and player as processes in
// lockstep (nothing lost however slow the detector), scores the collected results with the official
// metric, then computes mCE/mRR against a baseline and writes the tables and the HTML report.
#pragma once

#include <array>
#include <atomic>
#include <string>
#include <vector>

#include "campaign/progress.hpp"
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
  std::string
      pipeline_file;  // one run's nodes (a launch file); "" = launch/benchmark.yaml built in
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
  std::string
      robustness_error;  // why mCE/mRR were not computed although corruptions were asked for
  scoring::RobustnessSummary robustness;
  std::string report_path;
};

// One run of the matrix: a condition and seed with the detector configuration it runs with. The
// list of them (plan_runs) is what `faultline benchmark` runs one after the other and what
// `faultline benchmark plan` hands to a cluster scheduler as independent units.
struct RunSpec {
  std::string name;        // its folder under <out>/runs/: "clean", "fog_mid", "fog_mid_s2", ...
  std::string corruption;  // RoboBEV name; "" = clean
  std::string level;       // "" for clean
  int seed = 1;
  std::string variant;                      // "" = the configured detector
  std::vector<std::string> variant_params;  // -p overrides of that detector configuration
};

// The runs of the matrix in order: clean, corruption x level x seed, then (variants, our detector
// only) the detector-configuration runs. A pure function of the options.
std::vector<RunSpec> plan_runs(const BenchmarkOptions& opts);

// The progress line for run `index` of `count`; eta_s < 0 leaves the ETA out.
std::string run_line(std::size_t index, std::size_t count, const ConditionResult& r,
                     double eta_s = -1);

// A missing node executable under opts.bin_dir is kNotFound naming it.
Status check_node_executables(const BenchmarkOptions& opts);

// Runs one run into <out>/runs/<name>/ (emptied first) and scores it. A failing run is a result
// with ok = false and the cause; `stop` ends it early ("stopped").
ConditionResult run_one(const BenchmarkOptions& opts, const RunSpec& run,
                        const std::atomic<bool>& stop);

// Everything after the runs, from their results in plan order: mCE/mRR, robustness.{md,csv,json},
// report.html and summary.json in opts.out_dir. A local run and a collected cluster campaign both
// end here, so the same results give the same files. Fails only on a bad --baseline manifest.
Result<BenchmarkResult> finish_benchmark(const BenchmarkOptions& opts,
                                         std::vector<ConditionResult> runs,
                                         const ProgressLine& progress);

// Runs the whole matrix; progress lines go to `progress`. Fails only on setup problems (a missing
// node executable, an unwritable output dir); a failing run is recorded and the matrix continues.
// Each run also leaves its run.json record (benchmark_plan.hpp), as a cluster unit does.
Result<BenchmarkResult> run_benchmark(const BenchmarkOptions& opts, const std::atomic<bool>& stop,
                                      const ProgressLine& progress);

// The partial summary.json written after each run of a local benchmark (no robustness yet).
std::string summary_json(const BenchmarkOptions& opts, const BenchmarkResult& result);

// The injector's corruption name for a RoboBEV name (low_light -> dark).
std::string injector_corruption_name(const std::string& robobev_name);

}  // namespace faultline::campaign
