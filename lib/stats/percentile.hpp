// Exact percentiles of a sample held in memory: repeated timings of a benchmark, one run's
// per-frame latencies. For an unbounded stream use LogHistogram (histogram.hpp); the topic probes
// use nearest_rank (topic_meter.hpp).
#pragma once

#include <vector>

namespace faultline::stats {

// Where a percentile falls between the sorted values v[0..n-1], at the position q * (n - 1).
enum class Interpolation {
  // Between the two neighbours (numpy.percentile's default): an even count's median is the mean of
  // the two middle values.
  Linear,
  // The value at the position rounded half up, always a measured one: an even count's median is the
  // upper of the two middle values.
  NearestHalfUp,
};

// q in [0, 1] (clamped); 0 when `values` is empty. Sorts its own copy: the caller's order is kept.
double percentile(std::vector<double> values, double q, Interpolation how = Interpolation::Linear);

// percentile(values, 0.5, how).
double median(std::vector<double> values, Interpolation how = Interpolation::Linear);

}  // namespace faultline::stats
