// Low light: the per-value lambda table and the two noise stages.
#include "corruption/dark.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "corruption/dark_sampler.hpp"
#include "rng/lane_rng.hpp"

namespace faultline::corruption {

DarkParams dark_params(int severity) {
  static constexpr double kC[] = {0.60, 0.50, 0.40, 0.30, 0.20, 0.10};
  static constexpr double kP[] = {60, 25, 12, 5, 3, 1.5};
  static constexpr double kS[] = {0.08, 0.12, 0.18, 0.26, 0.38, 0.54};
  const auto i = static_cast<std::size_t>(std::clamp(severity, 0, 5));
  return {kC[i], 10 * kP[i], 0.1 * kS[i]};
}

namespace {

void lambdas_for_range(double lo_u8, double hi_u8, int severity, double lambdas[256]) {
  const DarkParams p = dark_params(severity);
  const double lo = lo_u8 / 255.0, hi = hi_u8 / 255.0;
  for (int v = 0; v < 256; ++v) {
    double y = 0.0;
    if (hi > lo) {
      const double t = (v / 255.0 - lo) / (hi - lo);
      y = (t * t) * p.target_max;
      y = (y * 255.0) / 255.0;
    }
    lambdas[v] = y * p.poisson_scale;
  }
}

}  // namespace

void dark_lambdas(int lo_u8, int hi_u8, int severity, double lambdas[256]) {
  lambdas_for_range(lo_u8, hi_u8, severity, lambdas);
}

void dark_lambdas(const cv::Mat& bgr, int severity, double lambdas[256]) {
  double lo_u8 = 0.0, hi_u8 = 0.0;
  cv::minMaxLoc(bgr.reshape(1), &lo_u8, &hi_u8);
  lambdas_for_range(lo_u8, hi_u8, severity, lambdas);
}

namespace {

double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

// Distribution of trunc(255 * clip(y + N(0, sigma), 0, 1)) over 0..255.
void noise_row(double y, double sigma, double* prob) {
  double prev = 0.0;  // P(out <= j - 1)
  for (int j = 0; j < 256; ++j) {
    const double cdf = j == 255 ? 1.0 : normal_cdf(((j + 1) / 255.0 - y) / sigma);
    prob[j] = std::max(cdf - prev, 0.0);
    prev = cdf;
  }
}

// Output distribution per input level. It depends only on (severity, image min, image max), which
// are the same for most frames of a stream, so the last few table sets are kept for reuse.
struct DarkTables {
  int severity = 0, lo = 0, hi = 0;
  // 256 packed alias entries per input level v, row v - lo, for lo <= v <= hi (no other level
  // occurs in the image).
  std::vector<std::uint32_t> entries;
};

std::shared_ptr<const DarkTables> build_tables(int severity, int lo, int hi) {
  const DarkParams p = dark_params(severity);
  double lam[256];
  lambdas_for_range(lo, hi, severity, lam);
  // Noise rows per Poisson count k (the value k / P is what the read noise is added to).
  const double max_lam = *std::max_element(lam, lam + 256);
  const int k_max = static_cast<int>(max_lam + 12.0 * std::sqrt(max_lam) + 12.0);
  std::vector<double> rows(static_cast<std::size_t>(k_max + 1) * 256);
  for (int k = 0; k <= k_max; ++k) {
    const double y = std::min(std::max(k / p.poisson_scale, 0.0), 1.0);
    noise_row(y, p.sigma, rows.data() + static_cast<std::size_t>(k) * 256);
  }
  auto t = std::make_shared<DarkTables>();
  t->severity = severity, t->lo = lo, t->hi = hi;
  t->entries.resize(static_cast<std::size_t>(hi - lo + 1) * 256);
  std::array<double, 256> mix{};
  for (int v = lo; v <= hi; ++v) {
    mix.fill(0.0);
    const double l = lam[v];
    double pk = std::exp(-l);  // Poisson pmf by recurrence
    for (int k = 0; k <= k_max; ++k) {
      if (k > 0) pk *= l / k;
      if (pk < 1e-15 && k > l) break;
      if (pk < 1e-15) continue;
      const double* row = rows.data() + static_cast<std::size_t>(k) * 256;
      for (int j = 0; j < 256; ++j) mix[static_cast<std::size_t>(j)] += pk * row[j];
    }
    build_alias_entries(mix.data(), t->entries.data() + static_cast<std::size_t>(v - lo) * 256);
  }
  return t;
}

std::shared_ptr<const DarkTables> tables_for(int severity, int lo, int hi) {
  static std::mutex mutex;
  static std::deque<std::shared_ptr<const DarkTables>> cache;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    for (const auto& t : cache) {
      if (t->severity == severity && t->lo == lo && t->hi == hi) return t;
    }
  }
  auto t =
      build_tables(severity, lo, hi);  // outside the lock: other streams keep sampling meanwhile
  const std::lock_guard<std::mutex> lock(mutex);
  cache.push_front(t);
  if (cache.size() > 8) cache.pop_back();
  return t;
}

}  // namespace

cv::Mat dark_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const cv::Mat in = bgr.isContinuous() ? bgr : bgr.clone();
  const std::size_t n = in.total() * 3;
  const auto [lo, hi] = dark_min_max(in.data, n);
  const auto tables = tables_for(severity, lo, hi);
  cv::Mat out(in.size(), in.type());
  rng::LaneRng lanes(rng);
  dark_sample(tables->entries.data(), lo, in.data, out.data, n, lanes);
  return out;
}

}  // namespace faultline::corruption
