// AP, TP errors, mAP, mTP, NDS from the curves (spec §6) and the two output files' layout.
#pragma once

#include <rapidjson/document.h>

#include <array>
#include <string>

#include "scoring/accumulate.hpp"
#include "scoring/detection_config.hpp"

namespace faultline::scoring {

// All 40 curves: [class][threshold], class and threshold in config order.
using MetricDataList = std::array<std::array<MetricData, kNumDistThs>, kNumClasses>;

struct DetectionMetrics {
  std::array<std::array<double, kNumDistThs>, kNumClasses> label_aps{};
  std::array<std::array<double, kNumTpMetrics>, kNumClasses> label_tp_errors{};  // TpMetric order
  std::array<double, kNumClasses> mean_dist_aps{};
  double mean_ap = 0;
  std::array<double, kNumTpMetrics> tp_errors{};
  std::array<double, kNumTpMetrics> tp_scores{};
  double nd_score = 0;
  double eval_time_s = 0;
};

double calc_ap(const MetricData& md);  // min_recall / min_precision 0.1
double calc_tp(const MetricData& md,
               TpMetric metric);  // mean from index 11 to the last non-zero confidence
DetectionMetrics compute_metrics(const MetricDataList& curves);

// metrics_summary.json text; `meta_json` is the submission meta re-serialised (PyJsonWriter).
std::string summary_json(const DetectionMetrics& m, const rapidjson::Value* meta);
std::string details_json(const MetricDataList& curves);
// The devkit console summary (mAP ... NDS, Eval time, per-class table).
std::string summary_table(const DetectionMetrics& m);

}  // namespace faultline::scoring
