// Collects the scored runs of one detector (clean + corruption x level) into DetectorScores.
// A manifest (YAML or JSON) maps condition names to run folders, each holding metrics_summary.json:
//   detector: bevdet            # optional name
//   latency_ms: 85.0            # optional, for speed/accuracy charts
//   runs: {clean: runs/clean, fog/easy: runs/fog_easy, ...}   # or these keys at the top level
// Relative folders are resolved against the manifest's folder.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "common/status.hpp"
#include "scoring/robustness.hpp"

namespace faultline::scoring {

// condition ("clean", "fog/easy", "MotionBlur/hard") and run folder.
using ConditionRun = std::pair<std::string, std::string>;

Result<std::vector<ConditionRun>> read_run_manifest(const std::string& path, std::string* detector,
                                                    double* latency_ms);
// Condition from a folder name: ".../fog/easy" -> fog/easy, ".../fog_easy" -> fog/easy,
// ".../clean".
std::string condition_from_path(const std::string& dir);
// Reads every run's nd_score and groups by corruption (levels in easy/mid/hard order). Needs
// "clean".
Result<DetectorScores> collect_detector_scores(const std::string& name,
                                               const std::vector<ConditionRun>& runs);

}  // namespace faultline::scoring
