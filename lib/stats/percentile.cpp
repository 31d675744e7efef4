#include "stats/percentile.hpp"

#include <algorithm>
#include <utility>

namespace faultline::stats {

double percentile(std::vector<double> values, double q, Interpolation how) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  if (how == Interpolation::NearestHalfUp) {
    return values[std::min(values.size() - 1, static_cast<std::size_t>(pos + 0.5))];
  }
  const auto lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  // (1 - f) a + f b, not a + f (b - a): for f = 0.5 it is exactly (a + b) / 2, the textbook median.
  return (1.0 - frac) * values[lo] + frac * values[hi];
}

double median(std::vector<double> values, Interpolation how) {
  return percentile(std::move(values), 0.5, how);
}

}  // namespace faultline::stats
