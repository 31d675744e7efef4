// The benchmarks' frames: the noisy road scene deterministic per spec, varied by seed, noise
// bounded by FrameSpec::noise, and the default spec still the frame the published worst-case `bench
// corrupt` figures were measured on; the realistic frames (every bench command's default) weighing
// what nuScenes' JPEGs weigh.
#include "bench/frames.hpp"

#include <gtest/gtest.h>

#include <cstdint>

#include "codec/jpeg.hpp"

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

// Every speed figure is measured on these: each of the six camera mounts at 1600x900 gives a JPEG
// in nuScenes' 130-165 KB (the noisy scene is 2.5-4x heavier, the flat render half as heavy).
TEST(RealisticFrameTest, FullSizeJpegsOfEveryMountWeighWhatNuScenesImagesWeigh) {
  for (std::uint64_t seed = 0; seed < 12; ++seed) {
    BenchFrame f;
    f.seed = seed;
    const auto jpeg = bench_jpeg(f);
    ASSERT_TRUE(jpeg.is_ok()) << jpeg.status().to_string();
    const double kb = static_cast<double>(jpeg->size()) / 1024.0;
    EXPECT_GE(kb, 130.0) << "seed " << seed;
    EXPECT_LE(kb, 165.0) << "seed " << seed;
    const auto decoded = codec::decode_jpeg(jpeg->data(), jpeg->size());
    ASSERT_TRUE(decoded.is_ok());
    EXPECT_EQ(decoded->cols, 1600);
    EXPECT_EQ(decoded->rows, 900);
  }
}

TEST(RealisticFrameTest, SameSeedSameBytesOtherSeedOtherFrame) {
  const cv::Mat a = realistic_frame(320, 180, 3);
  ASSERT_EQ(a.cols, 320);
  ASSERT_EQ(a.rows, 180);
  ASSERT_EQ(a.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(a, realistic_frame(320, 180, 3), cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(a, realistic_frame(320, 180, 4), cv::NORM_INF), 0);
}

TEST(BenchFrameTest, NoisyKindIsTheRoadSceneAtItsNoiseAndQuality) {
  BenchFrame f;
  f.kind = FrameKind::kNoisy;
  f.width = 320;
  f.height = 180;
  f.seed = 5;
  f.noisy_noise = 2;
  f.noisy_quality = 80;
  EXPECT_EQ(cv::norm(bench_pixels(f), synthetic_frame(Spec(5, 2)), cv::NORM_INF), 0);
  const auto jpeg = bench_jpeg(f);
  ASSERT_TRUE(jpeg.is_ok());
  const auto expected = codec::encode_jpeg(synthetic_frame(Spec(5, 2)), 80);
  ASSERT_TRUE(expected.is_ok());
  EXPECT_EQ(*jpeg, *expected);
}

TEST(BenchFrameTest, RejectsTinyFramesAndBadQuality) {
  BenchFrame f;
  f.width = 8;
  EXPECT_EQ(bench_jpeg(f).status().code(), StatusCode::kInvalidArgument);
  f.width = 64;
  f.kind = FrameKind::kNoisy;
  f.noisy_quality = 101;
  EXPECT_EQ(bench_jpeg(f).status().code(), StatusCode::kInvalidArgument);
}

TEST(BenchFrameTest, KindNamesRoundTrip) {
  for (FrameKind k : {FrameKind::kRealistic, FrameKind::kNoisy})
    EXPECT_EQ(frame_kind_from_string(to_string(k)), k);
  EXPECT_FALSE(frame_kind_from_string("Realistic").has_value());
  EXPECT_FALSE(frame_kind_from_string("").has_value());
}

}  // namespace
}  // namespace faultline::bench
