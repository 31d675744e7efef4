// NumpyRandomState against numpy_rng_vectors.json: raw MT19937, random_sample, polar normals with
// their cache, Poisson on both sides of the lambda = 10 switch (with the uniforms consumed),
// choice(6).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "rng/golden_json.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::rng {
namespace {

using faultline::testing::exact_double;
using faultline::testing::load_golden_json;

class NumpyRngVectorsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    doc_ = new rapidjson::Document(load_golden_json("numpy_rng_vectors.json"));
  }
  static void TearDownTestSuite() {
    delete doc_;
    doc_ = nullptr;
  }
  static const rapidjson::Value& seeds() { return (*doc_)["per_seed"]; }
  static rapidjson::Document* doc_;
};
rapidjson::Document* NumpyRngVectorsTest::doc_ = nullptr;

TEST_F(NumpyRngVectorsTest, RawMt19937OutputsMatch) {
  for (const auto& s : seeds().GetArray()) {
    NumpyRandomState rng(s["seed"].GetUint());
    for (const auto& v : s["mt19937_uint32"].GetArray()) EXPECT_EQ(rng.next_u32(), v.GetUint());
  }
}

TEST_F(NumpyRngVectorsTest, RandomSampleMatchesBitForBit) {
  for (const auto& s : seeds().GetArray()) {
    NumpyRandomState rng(s["seed"].GetUint());
    for (const auto& v : s["random_sample"]["hex"].GetArray())
      EXPECT_EQ(rng.random_sample(), exact_double(v));
  }
}

TEST_F(NumpyRngVectorsTest, StandardNormalsIncludingCachedValues) {
  for (const auto& s : seeds().GetArray()) {
    NumpyRandomState rng(s["seed"].GetUint());
    int i = 0;
    for (const auto& v : s["standard_normal"]["hex"].GetArray()) {
      EXPECT_EQ(rng.standard_normal(), exact_double(v))
          << "seed " << s["seed"].GetUint() << " normal " << i;
      ++i;
    }
    EXPECT_EQ(i, 21);
    EXPECT_TRUE(rng.gauss_cache_pending());  // the 21st value opened a new pair
  }
}

TEST_F(NumpyRngVectorsTest, PoissonValuesAndConsumption) {
  for (const auto& s : seeds().GetArray()) {
    for (const auto& lam : s["poisson"].GetObject()) {
      NumpyRandomState rng(s["seed"].GetUint());
      const double lambda = std::strtod(lam.name.GetString(), nullptr);
      int i = 0;
      for (const auto& v : lam.value["values"].GetArray()) {
        EXPECT_EQ(rng.poisson(lambda), v.GetInt64()) << "lambda " << lambda << " draw " << i;
        ++i;
      }
      EXPECT_EQ(rng.random_sample(), exact_double(lam.value["next_random_sample"]))
          << "lambda " << lambda;
    }
  }
}

TEST_F(NumpyRngVectorsTest, ChoiceOfSix) {
  for (const auto& s : seeds().GetArray()) {
    NumpyRandomState rng(s["seed"].GetUint());
    for (const auto& v : s["choice6"].GetArray()) EXPECT_EQ(rng.choice6(), v.GetInt());
  }
}

// randint(0, 6) is choice(6)'s draw (NumPy's masked rejection with mask 7), so the reference's
// vectors hold for it; randint(-d, d) offsets the same draws; a one-value range consumes nothing.
TEST_F(NumpyRngVectorsTest, RandintIsMaskedRejection) {
  for (const auto& s : seeds().GetArray()) {
    NumpyRandomState rng(s["seed"].GetUint());
    for (const auto& v : s["choice6"].GetArray()) EXPECT_EQ(rng.randint(0, 6), v.GetInt());
    NumpyRandomState a(s["seed"].GetUint()), b(s["seed"].GetUint());
    for (int i = 0; i < 50; ++i) EXPECT_EQ(a.randint(-3, 3), b.randint(0, 6) - 3);
  }
  NumpyRandomState r(1), fresh(1);
  EXPECT_EQ(r.randint(7, 8), 7);
  EXPECT_EQ(r.next_u32(), fresh.next_u32());
  // A range of 2^32 values takes one 32-bit draw as is; wider ranges take 64-bit draws (high word
  // first).
  NumpyRandomState w(5), w_ref(5);
  EXPECT_EQ(w.randint(0, std::int64_t{1} << 32), static_cast<std::int64_t>(w_ref.next_u32()));
  const std::int64_t wide = w.randint(0, (std::int64_t{1} << 40) + 1);
  EXPECT_GE(wide, 0);
  EXPECT_LE(wide, std::int64_t{1} << 40);
}

TEST(Mt19937Test, BlockGeneratorEqualsStdMt19937) {
  for (std::uint32_t seed : {0u, 1u, 5489u, 4294967295u}) {
    Mt19937 mine(seed);
    std::mt19937 ref(seed);
    for (int i = 0; i < 5000; ++i) ASSERT_EQ(mine(), ref()) << "seed " << seed << " output " << i;
  }
}

TEST(NumpyRandomStateTest, PreparedPoissonEqualsPlainPoisson) {
  for (double lam : {0.0, 0.3, 4.0, 9.99, 10.0, 47.5, 125.0}) {
    NumpyRandomState a(3), b(3);
    const PoissonParams p = prepare_poisson(lam);
    for (int i = 0; i < 200; ++i) ASSERT_EQ(a.poisson(p), b.poisson(lam)) << lam;
  }
}

TEST(NumpyRandomStateTest, SeedingClearsTheNormalCache) {
  NumpyRandomState a(7);
  (void)a.standard_normal();
  ASSERT_TRUE(a.gauss_cache_pending());
  a.seed(7);
  EXPECT_FALSE(a.gauss_cache_pending());
  NumpyRandomState b(7);
  EXPECT_EQ(a.standard_normal(), b.standard_normal());
}

// The legacy polar method written out on random_sample(), independent of the block-access path.
class ReferencePolar {
 public:
  explicit ReferencePolar(NumpyRandomState& rng) : rng_(rng) {}
  double next() {
    if (has_) {
      has_ = false;
      return cached_;
    }
    double x1 = 0, x2 = 0, r2 = 0;
    do {
      x1 = 2.0 * rng_.random_sample() - 1.0;
      x2 = 2.0 * rng_.random_sample() - 1.0;
      r2 = x1 * x1 + x2 * x2;
    } while (r2 >= 1.0 || r2 == 0.0);
    const double f = std::sqrt(-2.0 * std::log(r2) / r2);
    cached_ = f * x1;
    has_ = true;
    return f * x2;
  }
  bool pending() const { return has_; }

 private:
  NumpyRandomState& rng_;
  bool has_ = false;
  double cached_ = 0;
};

TEST(NumpyRandomStateTest, BulkNormalsDrawAndSkipLikeSingleDraws) {
  // Segments of draws and skips (odd and even, crossing block boundaries), from an aligned and from
  // an odd stream position (one 32-bit draw first), each followed by single draws and a uniform.
  for (bool odd_start : {false, true}) {
    NumpyRandomState bulk(11), plain(11);
    if (odd_start) {
      EXPECT_EQ(bulk.next_u32(), plain.next_u32());
    }
    ReferencePolar ref(plain);
    std::vector<double> out;
    for (std::size_t n : {1, 2, 3, 1000, 313, 0, 7, 4096, 1, 1, 625, 20001, 2}) {
      const bool skip = n % 2 == 1 && n > 1;
      out.assign(n, 0.0);
      bulk.standard_normals(skip ? nullptr : out.data(), n);
      for (std::size_t i = 0; i < n; ++i) {
        const double expected = ref.next();
        if (!skip) {
          ASSERT_EQ(out[i], expected) << n << " " << i;
        }
      }
      ASSERT_EQ(bulk.gauss_cache_pending(), ref.pending()) << n;
      ASSERT_EQ(bulk.standard_normal(), ref.next()) << n;
    }
    EXPECT_EQ(bulk.random_sample(), plain.random_sample());
  }
}

// random_samples / skip_samples against one random_sample() at a time: from an aligned start, after
// an odd number of 32-bit draws, at a block's last doubles, and across many whole blocks (which
// skip_samples only twists).
TEST(NumpyRandomStateTest, BulkSamplesFillAndSkipLikeSingleDraws) {
  for (const int u32_first : {0, 1, 3, 620, 623, 624, 1247}) {
    for (const std::size_t n :
         {std::size_t{0}, std::size_t{1}, std::size_t{2}, std::size_t{311}, std::size_t{312},
          std::size_t{313}, std::size_t{5000}, std::size_t{100001}}) {
      NumpyRandomState one(77), bulk(77), skip(77);
      for (int i = 0; i < u32_first; ++i) {
        one.next_u32();
        bulk.next_u32();
        skip.next_u32();
      }
      std::vector<double> want(n), got(n);
      for (auto& v : want) v = one.random_sample();
      bulk.random_samples(got.data(), n);
      ASSERT_EQ(got, want) << u32_first << " " << n;
      skip.skip_samples(n);
      // The streams continue identically (both 32-bit and double draws).
      const std::uint32_t next = one.next_u32();
      ASSERT_EQ(bulk.next_u32(), next) << u32_first << " " << n;
      ASSERT_EQ(skip.next_u32(), next) << u32_first << " " << n;
      for (int k = 0; k < 700; ++k) {
        const double v = one.random_sample();
        ASSERT_EQ(bulk.random_sample(), v);
        ASSERT_EQ(skip.random_sample(), v) << u32_first << " " << n << " " << k;
      }
    }
  }
}

// poissons() against one poisson() call per element: a level table mixing lambda 0, the
// multiplication method, PTRS and lambdas whose counts pass 255 (kept aside), over many blocks,
// from aligned and odd stream positions.
TEST(NumpyRandomStateTest, BulkPoissonsEqualSingleDraws) {
  PoissonParams table[256];
  for (int v = 0; v < 256; ++v) {
    const double lam = v < 20    ? 0.0
                       : v < 120 ? (v - 20) * 0.1
                       : v < 250 ? 10.0 + (v - 120) * 0.7
                                 : 300.0 + v;
    table[v] = prepare_poisson(lam);
  }
  std::vector<std::uint8_t> level(60001);
  std::uint32_t s = 12345u;
  for (auto& l : level) {
    s ^= s << 13, s ^= s >> 17, s ^= s << 5;
    l = static_cast<std::uint8_t>((s >> 8) % 256u < 6u ? 250u + s % 6u
                                                       : (s >> 16) % 250u);  // few large lambdas
  }
  for (const int u32_first : {0, 1, 623}) {
    for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{97}, level.size()}) {
      NumpyRandomState bulk(5), one(5);
      for (int i = 0; i < u32_first; ++i) ASSERT_EQ(bulk.next_u32(), one.next_u32());
      std::vector<std::uint8_t> counts(n);
      std::vector<LargeCount> large;
      bulk.poissons(table, level.data(), n, counts.data(), large);
      std::size_t next_large = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const std::int64_t k = one.poisson(table[level[i]]);
        ASSERT_EQ(counts[i], std::min<std::int64_t>(k, 255)) << u32_first << " " << i;
        if (k >= 255) {
          ASSERT_LT(next_large, large.size());
          EXPECT_EQ(large[next_large].index, i);
          EXPECT_EQ(large[next_large].count, k);
          ++next_large;
        }
      }
      EXPECT_EQ(next_large, large.size());
      if (n == level.size()) {
        EXPECT_GT(large.size(), 100u);  // the large-count path was exercised
      }
      EXPECT_EQ(bulk.random_sample(), one.random_sample()) << u32_first << " " << n;
    }
  }
}

// polar_pairs + cache_pair_half against standard_normal(): the same values (f * x2, then f * x1),
// the same cache and the same stream afterwards, from aligned and odd positions and with a cached
// value already pending.
TEST(NumpyRandomStateTest, PolarPairsGiveTheNormalsOfSingleDraws) {
  for (const int u32_first : {0, 1}) {
    for (const std::size_t pairs :
         {std::size_t{1}, std::size_t{3}, std::size_t{155}, std::size_t{4000}}) {
      NumpyRandomState bulk(21), one(21);
      for (int i = 0; i < u32_first; ++i) ASSERT_EQ(bulk.next_u32(), one.next_u32());
      double z = 0.0;
      EXPECT_FALSE(bulk.take_cached_normal(z));
      std::vector<double> x(2 * pairs), r2(pairs);
      bulk.polar_pairs(x.data(), r2.data(), pairs);
      for (std::size_t q = 0; q < pairs; ++q) {
        const double f = polar_factor(r2[q]);
        ASSERT_EQ(f * x[2 * q], one.standard_normal()) << pairs << " " << q;
        ASSERT_EQ(f * x[2 * q + 1], one.standard_normal()) << pairs << " " << q;
      }
      // One more pair whose second half is left cached, as an odd normal count leaves it.
      bulk.polar_pairs(x.data(), r2.data(), 1);
      ASSERT_EQ(polar_factor(r2[0]) * x[0], one.standard_normal());
      bulk.cache_pair_half(x[1], r2[0]);
      ASSERT_TRUE(bulk.gauss_cache_pending());
      ASSERT_TRUE(one.gauss_cache_pending());
      ASSERT_TRUE(bulk.take_cached_normal(z));
      EXPECT_EQ(z, one.standard_normal());
      EXPECT_FALSE(bulk.take_cached_normal(z));
      EXPECT_EQ(bulk.random_sample(), one.random_sample());
    }
  }
}

TEST(NumpyLoggamTest, MatchesLgammaAtIntegers) {
  EXPECT_EQ(numpy_loggam(1.0), 0.0);
  EXPECT_EQ(numpy_loggam(2.0), 0.0);
  for (int k = 3; k < 300; ++k)
    EXPECT_NEAR(numpy_loggam(k), std::lgamma(static_cast<double>(k)), 1e-10) << k;
}

}  // namespace
}  // namespace faultline::rng
