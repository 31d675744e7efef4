// Pointwise noise: the reference's float64 arithmetic per element in numpy mode, per-level alias
// tables in fast mode.
#include "corruption/noise.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "corruption/dark_sampler.hpp"
#include "rng/lane_rng.hpp"

namespace faultline::corruption {
namespace {

std::size_t sev_index(int severity) {
  return static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1);
}

// np.uint8(np.clip(v, 0, 1) * 255): clip, scale, truncate.
inline std::uint8_t to_u8(double v) {
  return static_cast<std::uint8_t>(std::min(std::max(v, 0.0), 1.0) * 255.0);
}

cv::Mat continuous(const cv::Mat& m) { return m.isContinuous() ? m : m.clone(); }

// The Poisson stage shared by shot_noise and iso_noise: counts k ~ Poisson(v / 255 * scale) for
// every element, in memory order; counts of 255 and more saturate at 255 (both corruptions clip k /
// scale to 1 with scale <= 60).
std::vector<std::uint8_t> poisson_counts(const cv::Mat& in, double scale,
                                         rng::NumpyRandomState& rng) {
  rng::PoissonParams params[256];
  for (int v = 0; v < 256; ++v) params[v] = rng::prepare_poisson((v / 255.0) * scale);
  const std::size_t n = in.total() * 3;
  std::vector<std::uint8_t> counts(n);
  std::vector<rng::LargeCount> large;
  rng.poissons(params, in.data, n, counts.data(), large);
  return counts;
}

cv::Mat gaussian_like(const cv::Mat& in, double sigma, bool speckle, rng::NumpyRandomState& rng) {
  const std::size_t n = in.total() * 3;
  std::vector<double> z(n);
  rng.standard_normals(z.data(), n);
  cv::Mat out(in.size(), CV_8UC3);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = in.data[i] / 255.0;
    const double noise = 0.0 + sigma * z[i];  // normal(loc=0, scale=sigma)
    out.data[i] = to_u8(speckle ? x + x * noise : x + noise);
  }
  return out;
}

cv::Mat shot_numpy(const cv::Mat& in, int severity, rng::NumpyRandomState& rng) {
  const double c = shot_noise_scale(severity);
  const std::vector<std::uint8_t> k = poisson_counts(in, c, rng);
  std::uint8_t lut[256];
  for (int j = 0; j < 256; ++j) lut[j] = to_u8(j / c);
  cv::Mat out(in.size(), CV_8UC3);
  for (std::size_t i = 0; i < k.size(); ++i) out.data[i] = lut[k[i]];
  return out;
}

cv::Mat iso_numpy(const cv::Mat& in, int severity, rng::NumpyRandomState& rng) {
  constexpr double kPoisson = 25.0;
  const std::vector<std::uint8_t> k = poisson_counts(in, kPoisson, rng);
  // x = clip(k / 25, 0, 1) * 255., then x / 255.
  double level[256];
  for (int j = 0; j < 256; ++j)
    level[j] = (std::min(std::max(j / kPoisson, 0.0), 1.0) * 255.0) / 255.0;
  const double sigma = iso_noise_sigma(severity);
  std::vector<double> z(k.size());
  rng.standard_normals(z.data(), z.size());
  cv::Mat out(in.size(), CV_8UC3);
  for (std::size_t i = 0; i < k.size(); ++i)
    out.data[i] = to_u8(level[k[i]] + (0.0 + sigma * z[i]));
  return out;
}

// skimage.util.random_noise(mode='s&p', amount=p): flipped = choice([True, False], p=[p, 1 - p])
// over the whole array, then salted = choice([True, False], p=[0.5, 0.5]); numpy's choice is u <
// cdf[0] with cdf normalised by its last entry. Salt is 1, pepper 0 (the image is non-negative),
// the rest keeps x = v / 255.
cv::Mat impulse_numpy(const cv::Mat& in, int severity, rng::NumpyRandomState& rng) {
  const double p = impulse_noise_amount(severity);
  const double flip_below = p / (p + (1.0 - p));
  const double salt_below = 0.5 / (0.5 + 0.5);
  const std::size_t n = in.total() * 3;
  std::vector<double> u(n);
  rng.random_samples(u.data(), n);
  std::vector<std::uint8_t> flipped(n);
  for (std::size_t i = 0; i < n; ++i) flipped[i] = u[i] < flip_below ? 1 : 0;
  rng.random_samples(u.data(), n);
  cv::Mat out(in.size(), CV_8UC3);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = flipped[i] ? (u[i] < salt_below ? 1.0 : 0.0) : in.data[i] / 255.0;
    out.data[i] = to_u8(x);
  }
  return out;
}

double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

// Adds weight * P(trunc(255 * clip(y + N(0, sigma), 0, 1)) = j) to prob[j]; sigma 0 is a point
// mass.
void add_noise_row(double y, double sigma, double weight, double* prob) {
  if (sigma <= 0.0) {
    prob[to_u8(y)] += weight;
    return;
  }
  double prev = 0.0;  // P(out <= j - 1)
  for (int j = 0; j < 256; ++j) {
    const double cdf = j == 255 ? 1.0 : normal_cdf(((j + 1) / 255.0 - y) / sigma);
    prob[j] += weight * std::max(cdf - prev, 0.0);
    prev = cdf;
  }
}

// Poisson(lam) pmf by recurrence, handed to `emit(k, pk)` until the tail is negligible.
template <typename Emit>
void poisson_pmf(double lam, Emit emit) {
  if (lam <= 0.0) {
    emit(0, 1.0);
    return;
  }
  // log-space start keeps exp(-lam) representable for every lam used here (<= 60).
  double pk = std::exp(-lam);
  const int k_max = static_cast<int>(lam + 14.0 * std::sqrt(lam) + 20.0);
  for (int k = 0; k <= k_max; ++k) {
    if (k > 0) pk *= lam / k;
    if (pk > 0.0) emit(k, pk);
  }
}

struct LevelTables {
  std::vector<std::uint32_t> entries;  // 256 packed alias entries per input level 0..255
};

std::shared_ptr<const LevelTables> build_tables(Corruption c, int severity) {
  auto t = std::make_shared<LevelTables>();
  t->entries.resize(256 * 256);
  std::array<double, 256> prob{};
  for (int v = 0; v < 256; ++v) {
    pointwise_noise_distribution(c, severity, v, prob.data());
    build_alias_entries(prob.data(), t->entries.data() + static_cast<std::size_t>(v) * 256);
  }
  return t;
}

constexpr Corruption kNoises[] = {Corruption::GaussianNoise, Corruption::ShotNoise,
                                  Corruption::ImpulseNoise, Corruption::SpeckleNoise,
                                  Corruption::IsoNoise};

std::shared_ptr<const LevelTables> tables_for(Corruption c, int severity) {
  static std::mutex mutex;
  static std::array<std::shared_ptr<const LevelTables>, 5 * 5> cache;
  std::size_t slot = 0;
  while (kNoises[slot] != c) ++slot;
  slot = slot * 5 + sev_index(severity);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (cache[slot]) return cache[slot];
  }
  auto t = build_tables(c, severity);  // outside the lock; a racing builder makes the same table
  const std::lock_guard<std::mutex> lock(mutex);
  if (!cache[slot]) cache[slot] = t;
  return cache[slot];
}

}  // namespace

bool is_pointwise_noise(Corruption c) {
  return std::find(std::begin(kNoises), std::end(kNoises), c) != std::end(kNoises);
}

double gaussian_noise_sigma(int severity) {
  static constexpr double kC[] = {.08, .12, 0.18, 0.26, 0.38};
  return kC[sev_index(severity)];
}
double shot_noise_scale(int severity) {
  static constexpr double kC[] = {60, 25, 12, 5, 3};
  return kC[sev_index(severity)];
}
double impulse_noise_amount(int severity) {
  static constexpr double kC[] = {.03, .06, .09, 0.17, 0.27};
  return kC[sev_index(severity)];
}
double speckle_noise_sigma(int severity) {
  static constexpr double kC[] = {.15, .2, 0.35, 0.45, 0.6};
  return kC[sev_index(severity)];
}
double iso_noise_sigma(int severity) {
  static constexpr double kC[] = {0.12, 0.18, 0.26, 0.38, 0.54};
  return 0.7 * kC[sev_index(severity)];
}

cv::Mat pointwise_noise_numpy(const cv::Mat& bgr, Corruption c, int severity,
                              rng::NumpyRandomState& rng) {
  const cv::Mat in = continuous(bgr);
  switch (c) {
    case Corruption::GaussianNoise:
      return gaussian_like(in, gaussian_noise_sigma(severity), false, rng);
    case Corruption::SpeckleNoise:
      return gaussian_like(in, speckle_noise_sigma(severity), true, rng);
    case Corruption::ShotNoise:
      return shot_numpy(in, severity, rng);
    case Corruption::IsoNoise:
      return iso_numpy(in, severity, rng);
    case Corruption::ImpulseNoise:
      return impulse_numpy(in, severity, rng);
    default:
      return in.clone();
  }
}

void pointwise_noise_distribution(Corruption c, int severity, int v, double prob[256]) {
  std::fill(prob, prob + 256, 0.0);
  const double x = v / 255.0;
  switch (c) {
    case Corruption::GaussianNoise:
      add_noise_row(x, gaussian_noise_sigma(severity), 1.0, prob);
      return;
    case Corruption::SpeckleNoise:
      add_noise_row(x, x * speckle_noise_sigma(severity), 1.0, prob);
      return;
    case Corruption::ShotNoise: {
      const double s = shot_noise_scale(severity);
      poisson_pmf(x * s, [&](int k, double pk) { prob[to_u8(k / s)] += pk; });
      return;
    }
    case Corruption::IsoNoise: {
      const double sigma = iso_noise_sigma(severity);
      poisson_pmf(x * 25.0, [&](int k, double pk) {
        add_noise_row(std::min(k / 25.0, 1.0), sigma, pk, prob);
      });
      return;
    }
    case Corruption::ImpulseNoise: {
      const double p = impulse_noise_amount(severity);
      prob[0] += p / 2;
      prob[255] += p / 2;
      prob[to_u8(x)] += 1.0 - p;
      return;
    }
    default:
      prob[v] = 1.0;
      return;
  }
}

cv::Mat pointwise_noise_fast(const cv::Mat& bgr, Corruption c, int severity, rng::FastRng& rng) {
  const cv::Mat in = continuous(bgr);
  const auto tables = tables_for(c, severity);
  cv::Mat out(in.size(), CV_8UC3);
  rng::LaneRng lanes(rng);
  dark_sample(tables->entries.data(), 0, in.data, out.data, in.total() * 3, lanes);
  return out;
}

}  // namespace faultline::corruption
