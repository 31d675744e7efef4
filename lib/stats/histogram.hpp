// Running summaries (Welford) and a log-bucketed histogram for percentiles with bounded memory.
#pragma once

#include <cstdint>
#include <vector>

namespace faultline::stats {

struct Summary {
  std::uint64_t count = 0;
  double mean = 0, min = 0, max = 0, stddev = 0;  // population stddev; all 0 when count == 0
};

class RunningSummary {
 public:
  void add(double value);
  Summary summary() const;
  void reset() { *this = RunningSummary{}; }

 private:
  std::uint64_t count_ = 0;
  double mean_ = 0, m2_ = 0, min_ = 0, max_ = 0;
};

// Buckets grow geometrically by 2% from `min_value` (values below it share bucket 0, so choose it
// at the resolution you need, e.g. 1e-3 ms); a percentile is exact to within one bucket (~1%).
class LogHistogram {
 public:
  explicit LogHistogram(double min_value = 1e-3, double growth = 1.02, int buckets = 1500);
  void add(double value);
  // q in [0, 1]; 0 when empty. Returns the geometric middle of the bucket holding the q-quantile,
  // clamped to the observed min/max.
  double percentile(double q) const;
  std::uint64_t count() const { return count_; }
  void reset();

 private:
  double min_value_, log_growth_;
  std::vector<std::uint64_t> counts_;
  std::uint64_t count_ = 0;
  double seen_min_ = 0, seen_max_ = 0;
};

struct Percentiles {
  double p50 = 0, p95 = 0, p99 = 0;
};
Percentiles percentiles_of(const LogHistogram& h);

}  // namespace faultline::stats
