// Low light: the per-value lambda table and the two noise stages.
#include "corruption/dark.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace faultline::corruption {

DarkParams dark_params(int severity) {
  static constexpr double kC[] = {0.60, 0.50, 0.40, 0.30, 0.20, 0.10};
  static constexpr double kP[] = {60, 25, 12, 5, 3, 1.5};
  static constexpr double kS[] = {0.08, 0.12, 0.18, 0.26, 0.38, 0.54};
  const auto i = static_cast<std::size_t>(std::clamp(severity, 0, 5));
  return {kC[i], 10 * kP[i], 0.1 * kS[i]};
}

void dark_lambdas(const cv::Mat& bgr, int severity, double lambdas[256]) {
  const DarkParams p = dark_params(severity);
  double lo_u8 = 0.0, hi_u8 = 0.0;
  cv::minMaxLoc(bgr.reshape(1), &lo_u8, &hi_u8);
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

cv::Mat dark_exact(const cv::Mat& bgr, int severity, rng::NumpyRandomState& rng) {
  const DarkParams p = dark_params(severity);
  double lam[256];
  dark_lambdas(bgr, severity, lam);
  rng::PoissonParams prepared[256];
  for (int v = 0; v < 256; ++v) prepared[v] = rng::prepare_poisson(lam[v]);
  // y as a function of the count k, with the reference's arithmetic, for the counts that occur in practice.
  constexpr std::int64_t kTable = 1024;
  std::vector<double> y_of_k(kTable);
  auto y_for = [&](std::int64_t k) {
    return (std::min(std::max(static_cast<double>(k) / p.poisson_scale, 0.0), 1.0) * 255.0) / 255.0;
  };
  for (std::int64_t k = 0; k < kTable; ++k) y_of_k[static_cast<std::size_t>(k)] = y_for(k);
  const cv::Mat in = bgr.isContinuous() ? bgr : bgr.clone();
  const std::size_t n = in.total() * 3;
  std::vector<double> y(n);
  const std::uint8_t* src = in.data;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t k = rng.poisson(prepared[src[i]]);
    y[i] = k < kTable ? y_of_k[static_cast<std::size_t>(k)] : y_for(k);
  }
  cv::Mat out(in.size(), in.type());
  std::uint8_t* dst = out.data;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = y[i] + rng.normal(0.0, p.sigma);
    dst[i] = static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0);
  }
  return out;
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

// Walker alias table over 256 outcomes with 32-bit thresholds.
struct Alias {
  std::array<std::uint32_t, 256> threshold;
  std::array<std::uint8_t, 256> alias;
};

void build_alias(const double* prob, Alias& a) {
  std::array<double, 256> scaled{};
  double total = 0.0;
  for (int j = 0; j < 256; ++j) total += prob[j];
  std::array<int, 256> small{}, large{};
  int ns = 0, nl = 0;
  for (int j = 0; j < 256; ++j) {
    scaled[static_cast<std::size_t>(j)] = prob[j] / total * 256.0;
    a.alias[static_cast<std::size_t>(j)] = static_cast<std::uint8_t>(j);
    if (scaled[static_cast<std::size_t>(j)] < 1.0) {
      small[static_cast<std::size_t>(ns++)] = j;
    } else {
      large[static_cast<std::size_t>(nl++)] = j;
    }
  }
  while (ns > 0 && nl > 0) {
    const int s = small[static_cast<std::size_t>(--ns)];
    const int l = large[static_cast<std::size_t>(nl - 1)];
    a.threshold[static_cast<std::size_t>(s)] =
        static_cast<std::uint32_t>(std::min(scaled[static_cast<std::size_t>(s)] * 4294967296.0, 4294967295.0));
    a.alias[static_cast<std::size_t>(s)] = static_cast<std::uint8_t>(l);
    scaled[static_cast<std::size_t>(l)] -= 1.0 - scaled[static_cast<std::size_t>(s)];
    if (scaled[static_cast<std::size_t>(l)] < 1.0) {
      --nl;
      small[static_cast<std::size_t>(ns++)] = l;
    }
  }
  while (nl > 0) a.threshold[static_cast<std::size_t>(large[static_cast<std::size_t>(--nl)])] = 0xFFFFFFFFu;
  while (ns > 0) a.threshold[static_cast<std::size_t>(small[static_cast<std::size_t>(--ns)])] = 0xFFFFFFFFu;
}

}  // namespace

cv::Mat dark_fast(const cv::Mat& bgr, int severity, rng::FastRng& rng) {
  const DarkParams p = dark_params(severity);
  double lam[256];
  dark_lambdas(bgr, severity, lam);
  const cv::Mat in = bgr.isContinuous() ? bgr : bgr.clone();
  const std::size_t n = in.total() * 3;
  std::array<bool, 256> used{};
  for (std::size_t i = 0; i < n; ++i) used[in.data[i]] = true;
  // Noise rows per Poisson count k (the value k / P is what the read noise is added to).
  const double max_lam = *std::max_element(lam, lam + 256);
  const int k_max = static_cast<int>(max_lam + 12.0 * std::sqrt(max_lam) + 12.0);
  std::vector<double> rows(static_cast<std::size_t>(k_max + 1) * 256);
  for (int k = 0; k <= k_max; ++k) {
    const double y = std::min(std::max(k / p.poisson_scale, 0.0), 1.0);
    noise_row(y, p.sigma, rows.data() + static_cast<std::size_t>(k) * 256);
  }
  std::vector<Alias> tables(256);
  std::array<double, 256> mix{};
  for (int v = 0; v < 256; ++v) {
    if (!used[static_cast<std::size_t>(v)]) continue;
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
    build_alias(mix.data(), tables[static_cast<std::size_t>(v)]);
  }
  cv::Mat out(in.size(), in.type());
  std::uint8_t* dst = out.data;
  const std::uint8_t* src = in.data;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t r = rng.next_u64();
    const Alias& a = tables[src[i]];
    const auto bucket = static_cast<std::uint8_t>(r >> 56);
    const auto u = static_cast<std::uint32_t>(r);
    dst[i] = u <= a.threshold[bucket] ? bucket : a.alias[bucket];
  }
  return out;
}

}  // namespace faultline::corruption
