// The benchmarks' synthetic frame: deterministic per spec, varied by seed, noise bounded by
// FrameSpec::noise, and the default spec still the frame the published `bench corrupt` figures were
// measured on.
#include "bench/frames.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace faultline::bench {
namespace {

// FNV-1a over the pixel bytes.
std::uint64_t fingerprint(const cv::Mat& m) {
  std::uint64_t h = 14695981039346656037ull;
  for (int y = 0; y < m.rows; ++y) {
    const auto* p = m.ptr<std::uint8_t>(y);
    const std::size_t row_bytes = static_cast<std::size_t>(m.cols) * m.elemSize();
    for (std::size_t i = 0; i < row_bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
  }
  return h;
}

FrameSpec Spec(std::uint64_t seed, int noise, int width = 320, int height = 180) {
  FrameSpec s;
  s.width = width;
  s.height = height;
  s.seed = seed;
  s.noise = noise;
  return s;
}

TEST(SyntheticFrameTest, IsAColourFrameOfTheRequestedSize) {
  const cv::Mat f = synthetic_frame(Spec(1, 6, 64, 48));
  EXPECT_EQ(f.cols, 64);
  EXPECT_EQ(f.rows, 48);
  EXPECT_EQ(f.type(), CV_8UC3);
}

TEST(SyntheticFrameTest, SameSpecSameBytesOtherSeedOtherFrame) {
  const cv::Mat a = synthetic_frame(Spec(3, 6));
  EXPECT_EQ(cv::norm(a, synthetic_frame(Spec(3, 6)), cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(a, synthetic_frame(Spec(4, 6)), cv::NORM_INF), 0);
}

TEST(SyntheticFrameTest, NoiseMovesEachValueByAtMostItsAmplitude) {
  const cv::Mat clean = synthetic_frame(Spec(5, 0));
  for (int noise : {1, 6, 32}) {
    const double diff = cv::norm(synthetic_frame(Spec(5, noise)), clean, cv::NORM_INF);
    EXPECT_GT(diff, 0) << noise;
    EXPECT_LE(diff, noise) << noise;
  }
}

// docs/performance.md and bench/results/corrupt.json were measured on this frame (`bench corrupt`
// without --image).
TEST(SyntheticFrameTest, DefaultSpecIsTheCorruptBenchmarksFrame) {
  const cv::Mat f = synthetic_frame();
  ASSERT_EQ(f.cols, 1600);
  ASSERT_EQ(f.rows, 900);
  EXPECT_EQ(fingerprint(f), 0xbcda08f18d537f74ull);
}

}  // namespace
}  // namespace faultline::bench
