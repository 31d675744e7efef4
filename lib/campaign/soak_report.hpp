// Soak internals: what a soak run writes (per-loop submissions, the log's period lines, soak.json
// and periods.csv). Only soak*.cpp include this.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "campaign/soak.hpp"
#include "common/status.hpp"
#include "detection.pb.h"

namespace faultline::campaign::soak_detail {

// v with `prec` decimals (0 for a non-finite value).
std::string fmt(double v, int prec = 3);

// Writes one loop's detections as a nuScenes submission; samples without output get an empty list,
// so a detector that fell behind is scored on what it delivered.
Status write_loop_results(const std::string& path, const std::vector<std::string>& split_samples,
                          const std::unordered_map<std::string, msgs::DetectionArray>& got);

// One period as a log line.
std::string period_line(const SoakPeriod& p);

// The run's options and results as soak.json.
std::string soak_json(const SoakOptions& o, const SoakResult& r);

// The periods as CSV (periods.csv), one row per period.
std::string periods_csv(const SoakResult& r);

}  // namespace faultline::campaign::soak_detail
