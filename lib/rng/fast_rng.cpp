// xoshiro256++ seeding, ziggurat tables and tail, Poisson samplers for fast mode.
#include "rng/fast_rng.hpp"

#include <cmath>
#include <cstdlib>

namespace faultline::rng {

FastRng::FastRng(std::uint64_t seed) {
  std::uint64_t x = seed;
  for (auto& s : s_) s = splitmix64(x);
  // Ziggurat tables (Marsaglia & Tsang 2000, 128 layers).
  const double m1 = 2147483648.0;
  double dn = 3.442619855899, tn = dn;
  const double vn = 9.91256303526217e-3;
  const double q = vn / std::exp(-0.5 * dn * dn);
  kn_[0] = static_cast<std::uint32_t>((dn / q) * m1);
  kn_[1] = 0;
  wn_[0] = q / m1;
  wn_[127] = dn / m1;
  fn_[0] = 1.0;
  fn_[127] = std::exp(-0.5 * dn * dn);
  for (int i = 126; i >= 1; --i) {
    dn = std::sqrt(-2.0 * std::log(vn / dn + std::exp(-0.5 * dn * dn)));
    kn_[i + 1] = static_cast<std::uint32_t>((dn / tn) * m1);
    tn = dn;
    fn_[i] = std::exp(-0.5 * dn * dn);
    wn_[i] = dn / m1;
  }
}

double FastRng::normal_tail(std::int32_t hz, std::uint32_t iz) {
  const double r = 3.442620;
  for (;;) {
    const double x = hz * wn_[iz];
    if (iz == 0) {
      double tx = 0.0, ty = 0.0;
      do {
        tx = -std::log(1.0 - random_sample()) * 0.2904764;
        ty = -std::log(1.0 - random_sample());
      } while (ty + ty < tx * tx);
      return hz > 0 ? r + tx : -r - tx;
    }
    if (fn_[iz] + random_sample() * (fn_[iz - 1] - fn_[iz]) < std::exp(-0.5 * x * x)) return x;
    hz = static_cast<std::int32_t>(next_u32());
    iz = static_cast<std::uint32_t>(hz) & 127u;
    if (static_cast<std::uint32_t>(std::llabs(hz)) < kn_[iz]) return hz * wn_[iz];
  }
}

std::int64_t FastRng::poisson(double lam) {
  if (!(lam > 0.0)) return 0;
  if (lam < 10.0) {
    // Inversion by sequential search: one uniform per draw.
    const double u = random_sample();
    double p = std::exp(-lam);
    double cdf = p;
    std::int64_t k = 0;
    while (u > cdf && k < 1000) {
      ++k;
      p *= lam / static_cast<double>(k);
      cdf += p;
    }
    return k;
  }
  const double slam = std::sqrt(lam);
  const double loglam = std::log(lam);
  const double b = 0.931 + 2.53 * slam;
  const double a = -0.059 + 0.02483 * b;
  const double invalpha = 1.1239 + 1.1328 / (b - 3.4);
  const double vr = 0.9277 - 3.6224 / (b - 2);
  for (;;) {
    const double u = random_sample() - 0.5;
    const double v = random_sample();
    const double us = 0.5 - std::fabs(u);
    const auto k = static_cast<std::int64_t>(std::floor((2 * a / us + b) * u + lam + 0.43));
    if (us >= 0.07 && v <= vr) return k;
    if (k < 0 || (us < 0.013 && v > us)) continue;
    if ((std::log(v) + std::log(invalpha) - std::log(a / (us * us) + b)) <=
        (-lam + static_cast<double>(k) * loglam - std::lgamma(static_cast<double>(k + 1)))) {
      return k;
    }
  }
}

}  // namespace faultline::rng
