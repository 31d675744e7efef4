// The benchmarks' one synthetic camera frame: a road scene (sky gradient, buildings with lit
// windows, a road with lane marks, a red disc, a caption) under seeded sensor noise. Edges and
// noise give it the JPEG size and the decode and corruption costs of a nuScenes frame; the seed
// varies the buildings and the noise, so the cameras of a run send different frames.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

namespace faultline::bench {

struct FrameSpec {
  int width = 1600;        // pixels
  int height = 900;        // pixels
  std::uint64_t seed = 7;  // buildings and noise; the same spec always gives the same bytes
  // 8-bit levels: each value moves by a uniform integer in [-noise, noise] (saturating). More
  // noise, larger JPEGs: 1600x900 at quality 95 is ~560 KB at 6, ~370 KB at 2.
  int noise = 6;
};

// A BGR CV_8UC3 frame, deterministic per spec (no global random state).
cv::Mat synthetic_frame(const FrameSpec& spec = {});

}  // namespace faultline::bench
