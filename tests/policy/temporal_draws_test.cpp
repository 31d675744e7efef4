// Camera Crash sets and Frame Lost masks against the golden JSON (numpy mode), distributions in
// fast mode.
#include "policy/temporal_draws.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "rng/golden_json.hpp"

namespace faultline::policy {
namespace {

using faultline::testing::load_golden_json;

TEST(CameraCrashTest, DeadSetsMatchGoldenForEverySeedAndSeverity) {
  const auto doc = load_golden_json("camera_crash.json");
  int checked = 0;
  for (const auto& s : doc["per_seed"].GetArray()) {
    for (const auto& sev : s["by_severity"].GetObject()) {
      rng::NumpyRandomState rng(s["seed"].GetUint());
      const int severity = std::stoi(sev.name.GetString());
      const auto dead = draw_dead_cameras(severity, rng);
      std::vector<int> expected;
      for (const auto& v : sev.value["dead_cameras"].GetArray()) expected.push_back(v.GetInt());
      EXPECT_EQ(dead, expected) << "seed " << s["seed"].GetUint() << " severity " << severity;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 50);
}

TEST(FrameLostTest, MasksMatchGoldenForEverySeedAndSeverity) {
  const auto doc = load_golden_json("frame_lost.json");
  int checked = 0;
  for (const auto& s : doc["per_seed"].GetArray()) {
    for (const auto& sev : s["by_severity"].GetObject()) {
      rng::NumpyRandomState rng(s["seed"].GetUint());
      const int severity = std::stoi(sev.name.GetString());
      const auto masks = draw_lost_frames(severity, 50, rng);
      const auto& expected = sev.value["masks"];
      ASSERT_EQ(masks.size(), expected.Size());
      for (rapidjson::SizeType f = 0; f < expected.Size(); ++f) {
        std::string got;
        for (bool d : masks[f]) got += d ? '1' : '0';
        EXPECT_EQ(got, expected[f].GetString())
            << "seed " << s["seed"].GetUint() << " sev " << severity << " f " << f;
      }
      ++checked;
    }
  }
  EXPECT_EQ(checked, 15);
}

TEST(FrameLostTest, MasksNestAcrossSeveritiesForOneSeed) {
  for (int sev = 1; sev < 5; ++sev) {
    rng::NumpyRandomState a(9), b(9);
    const auto lo = draw_lost_frames(sev, 40, a);
    const auto hi = draw_lost_frames(sev + 1, 40, b);
    for (std::size_t f = 0; f < lo.size(); ++f) {
      for (int m = 0; m < kNumCameras; ++m) {
        if (lo[f][static_cast<std::size_t>(m)]) {
          EXPECT_TRUE(hi[f][static_cast<std::size_t>(m)]);
        }
      }
    }
  }
}

// Fast mode: the drop rate passes a binomial test at p = s/6 (|z| < 5 over 60000 draws).
class FastFrameLostTest : public ::testing::TestWithParam<int> {};
TEST_P(FastFrameLostTest, DropRateIsBinomialWithPSeverityOverSix) {
  const int sev = GetParam();
  rng::FastRng rng(123);
  const auto masks = draw_lost_frames(sev, 10000, rng);
  double dropped = 0;
  for (const auto& m : masks) {
    for (bool d : m) dropped += d;
  }
  const double n = 60000, p = sev / 6.0;
  const double z = (dropped - n * p) / std::sqrt(n * p * (1 - p));
  EXPECT_LT(std::fabs(z), 5.0) << "rate " << dropped / n;
}
INSTANTIATE_TEST_SUITE_P(Severities, FastFrameLostTest, ::testing::Values(1, 2, 3, 4, 5));

// Fast mode: distinct dead cameras after k draws follow P(n) = C(6,n) S(k,n) n! / 6^k (spec §8),
// mean 6(1-(5/6)^k).
TEST(FastCameraCrashTest, DistinctCountMeanMatchesWithReplacementDraws) {
  for (int k = 1; k <= 5; ++k) {
    rng::FastRng rng(77);
    const int trials = 20000;
    double sum = 0, sq = 0;
    for (int t = 0; t < trials; ++t) {
      const auto dead = draw_dead_cameras(k, rng);
      ASSERT_LE(dead.size(), static_cast<std::size_t>(k));
      for (std::size_t i = 1; i < dead.size(); ++i) ASSERT_LT(dead[i - 1], dead[i]);
      sum += static_cast<double>(dead.size());
      sq += static_cast<double>(dead.size() * dead.size());
    }
    const double mean = sum / trials;
    const double sd = std::sqrt(sq / trials - mean * mean);
    EXPECT_NEAR(mean, 6.0 * (1.0 - std::pow(5.0 / 6.0, k)), 5 * sd / std::sqrt(trials) + 1e-9)
        << "k " << k;
  }
}

TEST(CameraCrashTest, SeverityZeroDrawsNothing) {
  rng::NumpyRandomState a(5), b(5);
  EXPECT_TRUE(draw_dead_cameras(0, a).empty());
  EXPECT_EQ(a.next_u32(), b.next_u32());
}

}  // namespace
}  // namespace faultline::policy
