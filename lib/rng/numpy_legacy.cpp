// NumPy legacy transforms: polar normal, Poisson (multiplication and PTRS), loggam. Compiled
// without FP contraction.
#include "rng/numpy_legacy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "common/simd.hpp"

namespace faultline::rng {

namespace {

// The polar method's acceptance test, r2 in (0, 1).
inline bool polar_accepts(double a, double b) {
  const double r = a * a + b * b;
  return r < 1.0 && r != 0.0;
}

#if FAULTLINE_X86_SIMD

// Accepted attempts among four (eight doubles: x1, x2 of each attempt in turn), as a count. r2 is
// formed as x1^2 + x2^2 with each square rounded, as the scalar test does (the horizontal add only
// reorders operands of a commutative add).
FAULTLINE_TARGET("avx2,popcnt") inline int polar_accepts4(const double* d) {
  const __m256d one = _mm256_set1_pd(1.0), two = _mm256_set1_pd(2.0), zero = _mm256_setzero_pd();
  const __m256d x0 = _mm256_sub_pd(_mm256_mul_pd(two, _mm256_loadu_pd(d)), one);
  const __m256d x1 = _mm256_sub_pd(_mm256_mul_pd(two, _mm256_loadu_pd(d + 4)), one);
  const __m256d r = _mm256_hadd_pd(_mm256_mul_pd(x0, x0), _mm256_mul_pd(x1, x1));
  const __m256d ok =
      _mm256_and_pd(_mm256_cmp_pd(r, one, _CMP_LT_OQ), _mm256_cmp_pd(r, zero, _CMP_NEQ_UQ));
  return __builtin_popcount(static_cast<unsigned>(_mm256_movemask_pd(ok)));
}

// Skips whole chunks of four attempts from d[j..count) while they hold fewer than `pairs`
// acceptances; returns the new j and lowers `pairs` by the acceptances skipped.
FAULTLINE_TARGET("avx2,popcnt")
std::size_t skip_chunks_avx2(const double* d, std::size_t j, std::size_t count,
                             std::size_t& pairs) {
  for (; j + 8 <= count; j += 8) {
    const auto accepted = static_cast<std::size_t>(polar_accepts4(d + j));
    if (accepted >= pairs) break;
    pairs -= accepted;
  }
  return j;
}
#endif

}  // namespace

void NumpyRandomState::skip_polar_pairs(std::size_t pairs) {
  while (pairs > 0) {
    std::size_t count = 0;
    const double* d = mt_.block_doubles(count);
    std::size_t j = 0;
#if FAULTLINE_X86_SIMD
    if (common::cpu_has_avx2_popcnt()) j = skip_chunks_avx2(d, j, count, pairs);
#endif
    for (; pairs > 0 && j + 2 <= count; j += 2)
      pairs -= polar_accepts(2.0 * d[j] - 1.0, 2.0 * d[j + 1] - 1.0);
    mt_.advance_doubles(j);
    if (pairs > 0 && count - j < 2) {
      // An attempt straddling two blocks, or an odd stream position: one attempt the plain way.
      const double x1 = 2.0 * random_sample() - 1.0;
      const double x2 = 2.0 * random_sample() - 1.0;
      pairs -= polar_accepts(x1, x2);
    }
  }
}

double NumpyRandomState::cached_gauss() {
  has_gauss_ = false;
  if (gauss_deferred_) {
    gauss_deferred_ = false;
    gauss_ = polar_factor(r2_) * x1_;
  }
  return gauss_;
}

void NumpyRandomState::polar_pair(double& x1, double& x2, double& r2) {
  for (;;) {
    // Whole attempts inside the current block: two precomputed doubles each, no per-draw
    // bookkeeping.
    std::size_t count = 0;
    const double* d = mt_.block_doubles(count);
    std::size_t j = 0;
    for (; j + 2 <= count; j += 2) {
      const double a = 2.0 * d[j] - 1.0;
      const double b = 2.0 * d[j + 1] - 1.0;
      const double r = a * a + b * b;
      if (r < 1.0 && r != 0.0) {
        mt_.advance_doubles(j + 2);
        x1 = a, x2 = b, r2 = r;
        return;
      }
    }
    mt_.advance_doubles(j);
    if (count >= 2) continue;
    // An attempt straddling two blocks, or an odd stream position: one attempt the plain way.
    x1 = 2.0 * random_sample() - 1.0;
    x2 = 2.0 * random_sample() - 1.0;
    r2 = x1 * x1 + x2 * x2;
    if (r2 < 1.0 && r2 != 0.0) return;
  }
}

double NumpyRandomState::standard_normal() {
  if (has_gauss_) return cached_gauss();
  double x1 = 0.0, x2 = 0.0, r2 = 0.0;
  polar_pair(x1, x2, r2);
  const double f = polar_factor(r2);
  gauss_ = f * x1;
  has_gauss_ = true;
  return f * x2;
}

void NumpyRandomState::standard_normals(double* out, std::size_t n) {
  std::size_t i = 0;
  if (n > 0 && has_gauss_) {
    const double g = cached_gauss();  // evaluated even when skipped: cheap, and keeps one code path
    if (out != nullptr) out[0] = g;
    i = 1;
  }
  double x1 = 0.0, x2 = 0.0, r2 = 0.0;
  if (out != nullptr) {
    for (; i + 2 <= n; i += 2) {
      polar_pair(x1, x2, r2);
      const double f = polar_factor(r2);
      out[i] = f * x2;
      out[i + 1] = f * x1;
    }
  } else {
    skip_polar_pairs((n - i) / 2);
    i += (n - i) / 2 * 2;
  }
  if (i < n) {  // one value left: it opens a pair whose second value stays cached
    polar_pair(x1, x2, r2);
    has_gauss_ = true;
    if (out != nullptr) {
      const double f = polar_factor(r2);
      out[i] = f * x2;
      gauss_ = f * x1;
    } else {
      gauss_deferred_ = true;
      x1_ = x1, r2_ = r2;
    }
  }
}

void NumpyRandomState::polar_pairs(double* x, double* r2, std::size_t pairs) {
  std::size_t got = 0;
  while (got < pairs) {
    std::size_t count = 0;
    const double* d = mt_.block_doubles(count);
    std::size_t j = 0;
    // Every attempt is written at slot `got`, which moves on only when it was accepted (no branch
    // on acceptance).
    for (; j + 2 <= count && got < pairs; j += 2) {
      const double a = 2.0 * d[j] - 1.0;
      const double b = 2.0 * d[j + 1] - 1.0;
      const double r = a * a + b * b;
      x[2 * got] = b;
      x[2 * got + 1] = a;
      r2[got] = r;
      got += static_cast<std::size_t>(r < 1.0 && r != 0.0);
    }
    mt_.advance_doubles(j);
    if (got < pairs && count - j < 2) {  // straddling two blocks, or an odd stream position
      polar_pair(x[2 * got + 1], x[2 * got], r2[got]);
      ++got;
    }
  }
}

void Mt19937::seed(std::uint32_t seed) {
  state_[0] = seed;
  for (int i = 1; i < kN; ++i) {
    state_[i] =
        1812433253u * (state_[i - 1] ^ (state_[i - 1] >> 30)) + static_cast<std::uint32_t>(i);
  }
  index_ = kN;
}

namespace {

// The twist as two straight loops the compiler vectorises (the first reads only words it has not
// yet rewritten; the second reads words at distance 227, more than a vector apart).
FAULTLINE_CLONES("avx2") void twist(std::uint32_t* __restrict state) {
  constexpr int kN = 624, kM = 397;
  constexpr std::uint32_t kUpper = 0x80000000u, kLower = 0x7fffffffu, kMatrix = 0x9908b0dfu;
  int i = 0;
  for (; i < kN - kM; ++i) {
    const std::uint32_t y = (state[i] & kUpper) | (state[i + 1] & kLower);
    state[i] = state[i + kM] ^ (y >> 1) ^ ((0u - (y & 1u)) & kMatrix);
  }
  for (; i < kN - 1; ++i) {
    const std::uint32_t y = (state[i] & kUpper) | (state[i + 1] & kLower);
    state[i] = state[i - (kN - kM)] ^ (y >> 1) ^ ((0u - (y & 1u)) & kMatrix);
  }
  const std::uint32_t y = (state[kN - 1] & kUpper) | (state[0] & kLower);
  state[kN - 1] = state[kM - 1] ^ (y >> 1) ^ ((0u - (y & 1u)) & kMatrix);
}

inline std::uint32_t temper_word(std::uint32_t t) {
  t ^= t >> 11;
  t ^= (t << 7) & 0x9d2c5680u;
  t ^= (t << 15) & 0xefc60000u;
  return t ^ (t >> 18);
}

// random_sample() of the tempered pair (a, b): (a >> 5) < 2^27 and (b >> 6) < 2^26 convert exactly,
// the sum is exact and the division by 2^53 is exact scaling.
inline double pair_double(std::uint32_t a, std::uint32_t b) {
  return (static_cast<double>(a >> 5) * 67108864.0 + static_cast<double>(b >> 6)) /
         9007199254740992.0;
}

void temper_pairs_scalar(const std::uint32_t* state, double* pairs) {
  for (int k = 0; k < 312; ++k)
    pairs[k] = pair_double(temper_word(state[2 * k]), temper_word(state[2 * k + 1]));
}

#if FAULTLINE_X86_SIMD
// Four pairs per step, each pair as one 64-bit lane (a low, b high): a >> 5 and b >> 6 become
// doubles by OR-ing them into 2^52's mantissa and subtracting 2^52 (exact below 2^52), then the
// scalar formula.
FAULTLINE_TARGET("avx2") void temper_pairs_avx2(const std::uint32_t* state, double* pairs) {
  const __m256i m1 = _mm256_set1_epi32(static_cast<int>(0x9d2c5680u));
  const __m256i m2 = _mm256_set1_epi32(static_cast<int>(0xefc60000u));
  const __m256i low32 = _mm256_set1_epi64x(0xFFFFFFFFll);
  const __m256d two52 = _mm256_set1_pd(4503599627370496.0);
  const __m256i two52_bits = _mm256_castpd_si256(two52);
  const __m256d two26 = _mm256_set1_pd(67108864.0),
                inv_two53 = _mm256_set1_pd(1.0 / 9007199254740992.0);
  for (int k = 0; k < 624; k += 8) {
    __m256i t = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(state + k));
    t = _mm256_xor_si256(t, _mm256_srli_epi32(t, 11));
    t = _mm256_xor_si256(t, _mm256_and_si256(_mm256_slli_epi32(t, 7), m1));
    t = _mm256_xor_si256(t, _mm256_and_si256(_mm256_slli_epi32(t, 15), m2));
    t = _mm256_xor_si256(t, _mm256_srli_epi32(t, 18));
    const __m256i a = _mm256_srli_epi64(_mm256_and_si256(t, low32), 5);
    const __m256i b = _mm256_srli_epi64(t, 38);
    const __m256d ad = _mm256_sub_pd(_mm256_castsi256_pd(_mm256_or_si256(a, two52_bits)), two52);
    const __m256d bd = _mm256_sub_pd(_mm256_castsi256_pd(_mm256_or_si256(b, two52_bits)), two52);
    _mm256_storeu_pd(pairs + k / 2,
                     _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(ad, two26), bd), inv_two53));
  }
}
#endif

}  // namespace

void Mt19937::refill() {
  twist(state_);
#if FAULTLINE_X86_SIMD
  if (common::cpu_has_avx2()) {
    temper_pairs_avx2(state_, pairs_);
  } else {
    temper_pairs_scalar(state_, pairs_);
  }
#else
  temper_pairs_scalar(state_, pairs_);
#endif
  words_ready_ = false;
  index_ = 0;
}

void Mt19937::temper_words() {
  for (int k = 0; k < kN; ++k) out_[k] = temper_word(state_[k]);
  words_ready_ = true;
}

void Mt19937::fill_doubles(double* out, std::size_t n) {
  while (n > 0) {
    std::size_t avail = 0;
    const double* d = block_doubles(avail);
    if (d == nullptr) {  // odd position: one value by hand, then aligned again
      *out++ = next_double();
      --n;
      continue;
    }
    const std::size_t k = std::min(avail, n);
    std::memcpy(out, d, k * sizeof(double));
    advance_doubles(k);
    out += k;
    n -= k;
  }
}

void Mt19937::skip_doubles(std::size_t n) {
  if ((index_ & 1) != 0) {
    for (; n > 0 && (index_ & 1) != 0; --n) static_cast<void>(next_double());
  }
  const auto left = static_cast<std::size_t>(kN - index_) / 2;  // whole doubles left in this block
  if (n <= left) {
    index_ += 2 * static_cast<int>(n);
    return;
  }
  n -= left;
  constexpr std::size_t kPerBlock = kN / 2;
  for (; n >= kPerBlock; n -= kPerBlock)
    twist(state_);  // a block consumed whole: its words are never read
  index_ = kN;
  if (n > 0) {
    refill();
    index_ = 2 * static_cast<int>(n);
  }
}

PoissonParams prepare_poisson(double lam) {
  PoissonParams p;
  p.lam = lam;
  if (lam >= 10.0) {
    p.method = PoissonMethod::Ptrs;
    p.slam = std::sqrt(lam);
    p.loglam = std::log(lam);
    p.b = 0.931 + 2.53 * p.slam;
    p.a = -0.059 + 0.02483 * p.b;
    p.invalpha = 1.1239 + 1.1328 / (p.b - 3.4);
    p.vr = 0.9277 - 3.6224 / (p.b - 2);
    p.log_invalpha = std::log(p.invalpha);
  } else if (lam != 0.0) {  // negative or NaN lambdas (invalid in NumPy) keep the old one-uniform
                            // behaviour
    p.method = PoissonMethod::Multiplication;
    if (lam > 0.0) p.enlam = std::exp(-lam);
  }
  return p;
}

std::int64_t NumpyRandomState::poisson(double lam) { return poisson(prepare_poisson(lam)); }

std::int64_t NumpyRandomState::poisson(const PoissonParams& p) {
  switch (p.method) {
    case PoissonMethod::Ptrs:
      return poisson_ptrs(p);
    case PoissonMethod::Multiplication:
      return poisson_mult(p.enlam);
    case PoissonMethod::Zero:
      break;
  }
  return 0;
}

std::int64_t NumpyRandomState::poisson_mult(double enlam) {
  std::int64_t x = 0;
  double prod = 1.0;
  for (;;) {
    prod *= random_sample();
    if (prod > enlam) {
      x += 1;
    } else {
      return x;
    }
  }
}

namespace {

// numpy_loggam(k + 1) for the counts PTRS proposes in practice (same doubles, computed once).
constexpr std::int64_t kLoggamTable = 1024;
double loggam_of_count_plus_one(std::int64_t k) {
  static const std::array<double, kLoggamTable> table = [] {
    std::array<double, kLoggamTable> t{};
    for (std::int64_t j = 0; j < kLoggamTable; ++j)
      t[static_cast<std::size_t>(j)] = numpy_loggam(static_cast<double>(j + 1));
    return t;
  }();
  return k < kLoggamTable ? table[static_cast<std::size_t>(k)]
                          : numpy_loggam(static_cast<double>(k + 1));
}

// static_cast<int64_t>(std::floor(q)) without a libm call (the baseline ISA has no rounding
// instruction); values outside +-2^62 (us = 0 gives -inf) take std::floor's path.
inline std::int64_t floor_to_int64(double q) {
  if (!(q > -0x1p62 && q < 0x1p62)) return static_cast<std::int64_t>(std::floor(q));
  const auto k =
      static_cast<std::int64_t>(q);  // truncation: one above the floor for negative non-integers
  return static_cast<double>(k) > q ? k - 1 : k;
}

// exp(-2): from lambda 2 on, k >= 4 is common enough (P > 0.14) that the multiplication loop looks
// eight deep.
constexpr double kLongChainEnlam = 0.1353352832366127;

// One PTRS attempt on (u + 0.5, v) = two uniforms: true with k set when it accepts.
inline bool ptrs_attempt(const PoissonParams& p, double uniform_u, double v, std::int64_t& k) {
  const double u = uniform_u - 0.5;
  const double us = 0.5 - std::fabs(u);
  k = floor_to_int64((2 * p.a / us + p.b) * u + p.lam + 0.43);
  if (us >= 0.07 && v <= p.vr) return true;
  if (k < 0 || (us < 0.013 && v > us)) return false;
  return (std::log(v) + p.log_invalpha - std::log(p.a / (us * us) + p.b)) <=
         (-p.lam + static_cast<double>(k) * p.loglam - loggam_of_count_plus_one(k));
}

}  // namespace

std::int64_t NumpyRandomState::poisson_ptrs(const PoissonParams& p) {
  std::int64_t k = 0;
  for (;;) {
    const double u = random_sample();
    const double v = random_sample();
    if (ptrs_attempt(p, u, v, k)) return k;
  }
}

void NumpyRandomState::poissons(const PoissonParams* params, const std::uint8_t* level,
                                std::size_t n, std::uint8_t* counts,
                                std::vector<LargeCount>& large) {
  auto store = [&](std::size_t i, std::int64_t k) {
    if (k < 255) {
      counts[i] = static_cast<std::uint8_t>(k);
    } else {
      counts[i] = 255;
      large.push_back({i, k});
    }
  };
  // The block's doubles are copied with zeros behind them: a product chain always ends on a zero,
  // so the multiplication loop needs no bounds test; a chain that ran into the padding is redone
  // the plain way.
  constexpr std::size_t kBlockDoubles = 312, kPad = 12;
  alignas(32) double buf[kBlockDoubles + kPad];
  std::size_t i = 0;
  while (i < n) {
    std::size_t count = 0;
    const double* d = mt_.block_doubles(count);
    if (d == nullptr) {  // odd stream position: one element the plain way (it realigns on its first
                         // uniform)
      store(i, poisson(params[level[i]]));
      ++i;
      continue;
    }
    std::memcpy(buf, d, count * sizeof(double));
    std::fill(buf + count, buf + count + kPad, 0.0);
    std::size_t t = 0;  // doubles consumed from the block
    for (; i < n; ++i) {
      const PoissonParams& p = params[level[i]];
      std::int64_t k = 0;
      if (p.method == PoissonMethod::Multiplication) {
        // The products never grow (each factor is < 1), so the count of the first four above
        // exp(-lam) is k when the chain ends among them: no branch on k's value unless it is 4 or
        // more.
        const double* b = buf + t;
        const double e = p.enlam;
        const double p1 = b[0], p2 = p1 * b[1], p3 = p2 * b[2], p4 = p3 * b[3];
        std::size_t above = static_cast<std::size_t>(p1 > e) + static_cast<std::size_t>(p2 > e) +
                            static_cast<std::size_t>(p3 > e) + static_cast<std::size_t>(p4 > e);
        double prod = p4;
        std::size_t depth = 4;
        if (p.enlam <
            kLongChainEnlam) {  // larger lambdas: four more products before any branch on k
          const double p5 = p4 * b[4], p6 = p5 * b[5], p7 = p6 * b[6], p8 = p7 * b[7];
          above += static_cast<std::size_t>(p5 > e) + static_cast<std::size_t>(p6 > e) +
                   static_cast<std::size_t>(p7 > e) + static_cast<std::size_t>(p8 > e);
          prod = p8;
          depth = 8;
        }
        if (above == depth) {
          // Every product so far was above: continue the chain from the last one.
          while ((prod *= b[above]) > e) ++above;
        }
        if (t + above >= count) break;  // the chain ended in the padding: redone the plain way
        t += above + 1;
        k = static_cast<std::int64_t>(above);
      } else if (p.method == PoissonMethod::Ptrs) {
        std::size_t s = t;
        while (s + 2 <= count && !ptrs_attempt(p, buf[s], buf[s + 1], k)) s += 2;
        if (s + 2 > count) break;
        t = s + 2;
      }
      store(i, k);
    }
    mt_.advance_doubles(t);
    if (i < n) {  // this element's draws straddle the block end
      store(i, poisson(params[level[i]]));
      ++i;
    }
  }
}

double numpy_loggam(double x) {
  static constexpr double kA[10] = {
      8.333333333333333e-02, -2.777777777777778e-03, 7.936507936507937e-04, -5.952380952380952e-04,
      8.417508417508418e-04, -1.917526917526918e-03, 6.410256410256410e-03, -2.955065359477124e-02,
      1.796443723688307e-01, -1.39243221690590e+00};
  if (x == 1.0 || x == 2.0) return 0.0;
  std::int64_t n = 0;
  if (x < 7.0) n = static_cast<std::int64_t>(7 - x);
  double x0 = x + static_cast<double>(n);
  const double x2 = (1.0 / x0) * (1.0 / x0);
  const double lg2pi = 1.8378770664093453e+00;
  double gl0 = kA[9];
  for (int k = 8; k >= 0; --k) {
    gl0 *= x2;
    gl0 += kA[k];
  }
  double gl = gl0 / x0 + 0.5 * lg2pi + (x0 - 0.5) * std::log(x0) - x0;
  if (x < 7.0) {
    for (std::int64_t k = 1; k <= n; ++k) {
      gl -= std::log(x0 - 1.0);
      x0 -= 1.0;
    }
  }
  return gl;
}

std::int64_t NumpyRandomState::randint(std::int64_t low, std::int64_t high) {
  const auto rng = static_cast<std::uint64_t>(high - 1) - static_cast<std::uint64_t>(low);
  if (rng == 0) return low;
  std::uint64_t mask = rng;  // smallest 2^k - 1 >= rng
  for (int shift = 1; shift < 64; shift <<= 1) mask |= mask >> shift;
  std::uint64_t v = 0;
  if (rng <= 0xFFFFFFFFull) {
    if (rng == 0xFFFFFFFFull) return low + static_cast<std::int64_t>(next_u32());
    do {
      v = next_u32() & mask;
    } while (v > rng);
  } else {
    do {
      const std::uint64_t hi = next_u32();
      v = ((hi << 32) | next_u32()) & mask;
    } while (v > rng);
  }
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(low) + v);
}

}  // namespace faultline::rng
