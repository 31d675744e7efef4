#include "stats/histogram.hpp"

#include <algorithm>
#include <cmath>

namespace faultline::stats {

void RunningSummary::add(double value) {
  if (count_ == 0) {
    min_ = max_ = value;
  } else {
    min_ = std::min(min_, value);
    max_ = std::max(max_, value);
  }
  ++count_;
  const double delta = value - mean_;
  mean_ += delta / static_cast<double>(count_);
  m2_ += delta * (value - mean_);
}

Summary RunningSummary::summary() const {
  Summary s;
  s.count = count_;
  if (count_ == 0) return s;
  s.mean = mean_;
  s.min = min_;
  s.max = max_;
  s.stddev = std::sqrt(std::max(0.0, m2_ / static_cast<double>(count_)));
  return s;
}

LogHistogram::LogHistogram(double min_value, double growth, int buckets)
    : min_value_(min_value),
      log_growth_(std::log(growth)),
      counts_(static_cast<std::size_t>(buckets), 0) {}

void LogHistogram::add(double value) {
  std::size_t index = 0;
  if (value > min_value_) {
    const double i = std::floor(std::log(value / min_value_) / log_growth_) + 1;
    index = std::min(counts_.size() - 1, static_cast<std::size_t>(i));
  }
  ++counts_[index];
  seen_min_ = count_ == 0 ? value : std::min(seen_min_, value);
  seen_max_ = count_ == 0 ? value : std::max(seen_max_, value);
  ++count_;
}

double LogHistogram::percentile(double q) const {
  if (count_ == 0) return 0;
  const auto rank =
      static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_)));
  if (rank >= count_) return seen_max_;  // the largest sample is known exactly
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < counts_.size(); ++i) {
    seen += counts_[i];
    if (seen >= std::max<std::uint64_t>(rank, 1)) {
      // Bucket i > 0 covers [min*g^(i-1), min*g^i); report its geometric middle.
      const double mid =
          i == 0 ? seen_min_ : min_value_ * std::exp((static_cast<double>(i) - 0.5) * log_growth_);
      return std::clamp(mid, seen_min_, seen_max_);
    }
  }
  return seen_max_;
}

void LogHistogram::reset() {
  std::fill(counts_.begin(), counts_.end(), 0);
  count_ = 0;
  seen_min_ = seen_max_ = 0;
}

Percentiles percentiles_of(const LogHistogram& h) {
  return {h.percentile(0.50), h.percentile(0.95), h.percentile(0.99)};
}

}  // namespace faultline::stats
