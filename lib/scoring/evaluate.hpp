// The whole nuScenes detection evaluation (devkit DetectionEval.main): split resolution, submission
// validation, GT loading, filtering, 40 accumulations, metrics and the two output files.
//
// Where the devkit crashes, Faultline defines the outcome:
//  * a submission with no box at all is scored (every class with GT gets AP 0 and TP errors 1, NDS
//  0)
//    and a warning is logged; the devkit raises "Error: Invalid box type: None";
//  * a negative or missing detection_score is rejected with an error naming the sample and box; the
//    devkit may abort on an internal assertion.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "scoring/filter.hpp"
#include "scoring/metrics.hpp"
#include "scoring/submission.hpp"

namespace faultline::scoring {

struct EvalOptions {
  std::string results_path;  // submission JSON
  std::string dataroot;      // folder holding <version>/*.json
  std::string version = "v1.0-trainval";
  std::string eval_set =
      "val";               // predefined split name or a key of <dataroot>/<version>/splits.json
  std::string output_dir;  // metrics_summary.json / metrics_details.json; empty = do not write
  std::uint64_t max_results_bytes = kDefaultMaxResultsBytes;  // larger results files are refused
};

// Wall seconds per phase; GT loading overlaps submission parsing on a second thread.
struct EvalTimings {
  double submission_s = 0, ground_truth_s = 0, ground_truth_wait_s = 0, filter_s = 0,
         accumulate_s = 0;
};

struct EvalOutcome {
  DetectionMetrics metrics;
  EvalTimings timings;
  MetricDataList curves;
  FilterCounts pred_counts, gt_counts;
  std::size_t samples = 0;
  std::shared_ptr<rapidjson::Document> meta;
};

// The sample tokens a results file for `eval_set` must hold, in sample.json order: the scenes of a
// predefined split (version-checked as by the scorer) or of a splits.json key. Errors name the
// file.
Result<std::vector<std::string>> eval_set_samples(const std::string& dataroot,
                                                  const std::string& version,
                                                  const std::string& eval_set);

// Receives one progress line in the devkit's wording (no trailing newline), from the calling
// thread, as each stage starts or ends; the caller decides where it goes (stdout, a log file).
using EvalProgress = std::function<void(const std::string& line)>;

// Runs the evaluation, reporting its stages to `progress` (may be empty). Nothing is written to
// files or the console here; on failure the Status names the file or sample at fault.
Result<EvalOutcome> evaluate_detection(const EvalOptions& opts, const EvalProgress& progress = {});

// Writes metrics_summary.json and metrics_details.json into dir (created if needed).
Status write_eval_outputs(const EvalOutcome& outcome, const std::string& dir);

}  // namespace faultline::scoring
