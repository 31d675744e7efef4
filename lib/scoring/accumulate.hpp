// Greedy matching and the 101-point curves of one (class, distance threshold) pair (spec §5), and
// the numpy helpers they rely on (interp, linspace, pairwise-summed mean).
#pragma once

#include <array>
#include <vector>

#include "common/status.hpp"
#include "scoring/detection_config.hpp"
#include "scoring/eval_box.hpp"

namespace faultline::scoring {

using Curve = std::array<double, kCurvePoints>;

// devkit MetricData: recall grid, precision, confidence and the five TP-error curves (TpMetric
// order).
struct MetricData {
  Curve recall{}, precision{}, confidence{};
  std::array<Curve, kNumTpMetrics> tp{};
  // Index of the last non-zero confidence, 0 if none.
  int max_recall_ind() const;
  static MetricData no_predictions();
};

// numpy.interp(x, xs, ys, left, right) semantics, including runs of equal xs.
double np_interp(double x, const std::vector<double>& xs, const std::vector<double>& ys,
                 double left, double right);
// np.linspace(0, 1, 101)[i]
double recall_grid(int i);
// np.sum / np.mean with numpy's pairwise summation (first element + pairwise rest).
double np_sum(const double* v, std::size_t n);
double np_mean(const double* v, std::size_t n);

// Filtered GT indexed by GT sample, predictions whose match_sample is a GT sample index or -1.
// Fails only when a matched box has a size <= 0 (the devkit asserts there).
Result<MetricData> accumulate(const EvalBoxes& gt, const EvalBoxes& pred, int cls, double dist_th);
// All four thresholds of one class; sorts and indexes once (same results as four accumulate()
// calls).
Result<std::array<MetricData, kNumDistThs>> accumulate_class(const EvalBoxes& gt,
                                                             const EvalBoxes& pred, int cls);

}  // namespace faultline::scoring
