// One realistic camera frame of the synthetic dataset's world, without writing a dataset: the
// frame `faultline corrupt --gallery`, the benchmark report's thumbnails and the benchmarks
// (bench/frames) show corruptions on.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

namespace faultline::dataset {

// The sensor noise amplitude (8-bit levels) of a realistic frame: the synthetic dataset's default.
constexpr int kRealisticNoise = 4;

// A scene of the synthetic dataset's renderer (road, lane marks, shaded vehicles and
// pedestrians) seen by one of the six nuScenes-like camera mounts, under kRealisticNoise sensor
// noise: BGR CV_8UC3 of width x height (callers keep both >= 16). The seed picks the scene, the
// mount (seed % 6: front, front-right, front-left, back, back-left, back-right) and the time in
// the scene; the same arguments always give the same pixels.
cv::Mat realistic_frame(int width, int height, std::uint64_t seed);

}  // namespace faultline::dataset
