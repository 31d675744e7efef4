// The benchmarks' camera frames, from one place. Two kinds:
// - realistic (the default of every bench command): a scene of the synthetic dataset's renderer
// (road, lane marks,
//   shaded vehicles and pedestrians) seen by one of the six nuScenes camera mounts, under the
//   dataset's sensor noise (4 levels) and encoded at quality 90, as nuScenes ships its CAM_* JPEGs.
//   At 1600x900 these JPEGs weigh 130-165 KB, nuScenes' range, so decode and kernel costs are
//   measured on frames as costly as users' data.
// - noisy (the worst case): the older built-in road scene (sky gradient, buildings with lit
// windows, a road, a red
//   disc, a caption) under heavy seeded noise; 1600x900 at quality 95 is ~370 KB at noise 2 and
//   ~560 KB at 6.
// Both are deterministic per spec; the seed varies the scene, so the cameras of a run send
// different frames.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "dataset/synth_frame.hpp"

namespace faultline::bench {

// The noisy road scene's spec.
struct FrameSpec {
  int width = 1600;        // pixels
  int height = 900;        // pixels
  std::uint64_t seed = 7;  // buildings and noise; the same spec always gives the same bytes
  // 8-bit levels: each value moves by a uniform integer in [-noise, noise] (saturating). More
  // noise, larger JPEGs: 1600x900 at quality 95 is ~560 KB at 6, ~370 KB at 2.
  int noise = 6;
};

// The noisy road scene: a BGR CV_8UC3 frame, deterministic per spec (no global random state).
cv::Mat synthetic_frame(const FrameSpec& spec = {});

// The realistic frame's sensor noise (8-bit levels) and JPEG quality: the synthetic dataset's
// defaults.
constexpr int kRealisticNoise = dataset::kRealisticNoise;
constexpr int kRealisticQuality = 90;

// A realistic frame before encoding: BGR CV_8UC3 of width x height (>= 16 each). The seed picks the
// scene, the camera mount (seed % 6: front, front-right, front-left, back, back-left, back-right)
// and the time in the scene.
cv::Mat realistic_frame(int width, int height, std::uint64_t seed);

enum class FrameKind { kRealistic, kNoisy };

const char* to_string(FrameKind kind);  // "realistic" | "noisy"
std::optional<FrameKind> frame_kind_from_string(
    const std::string& name);  // nullopt for any other name

// One camera frame of a benchmark, as the bench commands send it.
struct BenchFrame {
  FrameKind kind = FrameKind::kRealistic;
  int width = 1600, height = 900;  // pixels
  std::uint64_t seed = 0;          // see realistic_frame / FrameSpec::seed
  // The noisy kind only (each command keeps the noise and quality its worst-case figures were
  // measured with).
  int noisy_noise = 6;
  int noisy_quality = 95;
};

// The frame's pixels before encoding (realistic_frame or synthetic_frame).
cv::Mat bench_pixels(const BenchFrame& frame);

// The frame's JPEG bytes: realistic at quality 90, noisy at noisy_quality. kInvalidArgument for a
// size below 16x16 or a quality outside 1..100.
Result<std::vector<std::uint8_t>> bench_jpeg(const BenchFrame& frame);

}  // namespace faultline::bench
