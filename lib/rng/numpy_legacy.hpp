// NumPy's legacy RandomState (np.random.*) on std::mt19937, bit-exact (spec corruptions.md §10).
// Used by numpy mode so a corruption seeded with np.random.seed(s) reproduces the Python reference
// draw for draw.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace faultline::rng {

// MT19937 with the reference's init_genrand seeding (== std::mt19937(seed) output for output). It
// twists 624 words at a time and tempers them straight into the block's 312 random_sample() doubles
// (AVX2 where available); the tempered 32-bit words themselves are made only if a single 32-bit
// draw asks for them. Faster than std::mt19937's per-call tempering on the millions of draws Dark,
// Fog and Snow make.
class Mt19937 {
 public:
  explicit Mt19937(std::uint32_t seed) { this->seed(seed); }
  void seed(std::uint32_t seed);
  std::uint32_t operator()() {
    if (index_ == kN) refill();
    if (!words_ready_) temper_words();
    return out_[index_++];
  }

  // random_sample() from the next two outputs: ((a >> 5) * 2^26 + (b >> 6)) / 2^53. When the two
  // outputs are an aligned pair of the current block (always, unless single 32-bit draws made the
  // position odd) the double was precomputed with the block (vectorised), which is the same value.
  double next_double() {
    if (index_ == kN) refill();
    if ((index_ & 1) == 0) {
      const double u = pairs_[index_ >> 1];
      index_ += 2;
      return u;
    }
    const std::uint32_t a = (*this)() >> 5;
    const std::uint32_t b = (*this)() >> 6;
    return (a * 67108864.0 + b) / 9007199254740992.0;
  }

  // Bulk access for tight loops: the precomputed next_double() values left in the current block (an
  // exhausted block is refilled first), or nullptr with count 0 when the position is odd (then only
  // next_double() applies). advance_doubles(k) consumes the first k of them (k <= count).
  const double* block_doubles(std::size_t& count) {
    if (index_ == kN) refill();
    if ((index_ & 1) != 0) {
      count = 0;
      return nullptr;
    }
    count = static_cast<std::size_t>(kN - index_) / 2;
    return pairs_ + index_ / 2;
  }
  void advance_doubles(std::size_t k) { index_ += 2 * static_cast<int>(k); }

  // n next_double() values in order into out[0..n).
  void fill_doubles(double* out, std::size_t n);
  // The state after n next_double() calls, without making the values: blocks passed over whole are
  // only twisted (no tempering, no conversion).
  void skip_doubles(std::size_t n);

 private:
  static constexpr int kN = 624;
  void refill();
  void temper_words();
  std::uint32_t state_[kN];
  std::uint32_t out_[kN];  // the block's tempered words, valid when words_ready_
  bool words_ready_ = false;
  double pairs_[kN / 2];  // pairs_[k] = the double from tempered words 2k, 2k + 1
  int index_ = kN;
};

// Poisson(lam) constants precomputed once per lambda with the reference's arithmetic (Dark has at
// most 256 distinct lambdas per image). Drawing from them is bit-identical to drawing with lam.
enum class PoissonMethod : std::uint8_t { Zero, Multiplication, Ptrs };
struct PoissonParams {
  double lam = 0;
  PoissonMethod method = PoissonMethod::Zero;
  double enlam = 1;  // exp(-lam), multiplication method
  double slam = 0, loglam = 0, b = 0, a = 0, invalpha = 0, vr = 0;  // PTRS
  double log_invalpha = 0;  // log(invalpha), the same double PTRS would compute per attempt
};
PoissonParams prepare_poisson(double lam);

// A Poisson count too large for a byte, kept aside by NumpyRandomState::poissons.
struct LargeCount {
  std::size_t index;
  std::int64_t count;
};

// The legacy polar method's scale for an accepted r2: sqrt(-2 ln(r2) / r2) with glibc's log.
inline double polar_factor(double r2) { return std::sqrt(-2.0 * std::log(r2) / r2); }

// Not thread-safe; one instance per image (numpy mode) or per sequence (temporal draws).
class NumpyRandomState {
 public:
  explicit NumpyRandomState(std::uint32_t seed) : mt_(seed) {}

  // np.random.seed(s): re-initialises the engine and clears the cached normal.
  void seed(std::uint32_t seed) {
    mt_.seed(seed);
    has_gauss_ = false;
    gauss_deferred_ = false;
  }

  std::uint32_t next_u32() { return mt_(); }

  // random_sample(): 53-bit double in [0, 1) from two consecutive outputs.
  double random_sample() { return mt_.next_double(); }
  // n random_sample() draws in order into out[0..n); skip_samples(n) leaves the stream where they
  // would have.
  void random_samples(double* out, std::size_t n) { mt_.fill_doubles(out, n); }
  void skip_samples(std::size_t n) { mt_.skip_doubles(n); }

  // uniform(lo, hi) = lo + (hi - lo) * u.
  double uniform(double lo, double hi) { return lo + (hi - lo) * random_sample(); }

  // standard_normal(): legacy polar method with its one-value cache.
  double standard_normal();

  // n standard_normal() draws in order into out[0..n), or, with out == nullptr, the same draws
  // skipped: the state afterwards (stream position and cache) is the same either way, but skipping
  // computes no logarithm (a value left in the cache is evaluated only if it is ever read).
  void standard_normals(double* out, std::size_t n);

  // normal(loc, scale) = loc + scale * standard_normal().
  double normal(double loc, double scale) { return loc + scale * standard_normal(); }

  // poisson(lam): 0 consumes nothing; lam < 10 multiplication method; lam >= 10 PTRS (Hormann).
  std::int64_t poisson(double lam);
  std::int64_t poisson(const PoissonParams& p);

  // n Poisson draws in order, element i from params[level[i]] (a table indexed by a byte): the same
  // counts and stream as n poisson() calls, in one loop over the generator's blocks. counts[i] =
  // min(k, 255); counts of 255 and more are also appended to `large` in index order.
  void poissons(const PoissonParams* params, const std::uint8_t* level, std::size_t n,
                std::uint8_t* counts, std::vector<LargeCount>& large);

  // For callers that evaluate the polar method themselves. polar_pairs draws the next `pairs`
  // accepted pairs as standard_normal() would (ignoring the cache): x[2q] = x2 and x[2q + 1] = x1
  // of pair q (the order their normals come out: f * x2, then f * x1) and r2[q], f =
  // polar_factor(r2[q]).
  void polar_pairs(double* x, double* r2, std::size_t pairs);
  // Takes the cached normal into z (and clears the cache) if there is one.
  bool take_cached_normal(double& z) {
    if (!has_gauss_) return false;
    z = cached_gauss();
    return true;
  }
  // Leaves f(r2) * x1 of a pair whose f * x2 the caller used as the cached normal, evaluated only
  // when read.
  void cache_pair_half(double x1, double r2) {
    has_gauss_ = true;
    gauss_deferred_ = true;
    x1_ = x1, r2_ = r2;
  }

  // choice(6) with replacement: masked rejection on 32-bit outputs.
  int choice6() {
    for (;;) {
      const std::uint32_t v = next_u32() & 7u;
      if (v <= 5u) return static_cast<int>(v);
    }
  }

  // randint(low, high) for the default int64 dtype (high exclusive): NumPy's masked rejection
  // sampling, 32-bit draws while high - low - 1 fits in 32 bits (64-bit draws beyond). A range of
  // one value draws nothing. Requires low < high.
  std::int64_t randint(std::int64_t low, std::int64_t high);

  bool gauss_cache_pending() const { return has_gauss_; }

 private:
  std::int64_t poisson_mult(double enlam);
  std::int64_t poisson_ptrs(const PoissonParams& p);
  // The next accepted polar pair (x1, x2 in draw order) and its r2 = x1^2 + x2^2.
  void polar_pair(double& x1, double& x2, double& r2);
  // Consumes the next `pairs` accepted polar pairs without evaluating them.
  void skip_polar_pairs(std::size_t pairs);
  double cached_gauss();

  Mt19937 mt_;
  bool has_gauss_ = false;
  bool gauss_deferred_ = false;  // the cached value is f(r2_) * x1_, not yet evaluated
  double gauss_ = 0.0;
  double x1_ = 0.0, r2_ = 0.0;
};

// NumPy's random_loggam (log-gamma used by PTRS).
double numpy_loggam(double x);

}  // namespace faultline::rng
