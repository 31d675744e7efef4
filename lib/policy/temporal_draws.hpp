// The two temporal faults' random draws (spec corruptions.md §8, §9), in RoboBEV's order:
// - camera_crash: `severity` draws of choice(6) WITH replacement, once per sequence; the dead set
// is the distinct
//   cameras drawn, so it can be smaller than the severity.
// - frame_lost: per frame, cameras 0..5 in order, one uniform each; dropped iff u < severity / 6.
// Camera order: CAM_FRONT, CAM_FRONT_RIGHT, CAM_FRONT_LEFT, CAM_BACK, CAM_BACK_LEFT,
// CAM_BACK_RIGHT. With a NumpyRandomState(seed) the results equal the reference's after
// np.random.seed(seed).
#pragma once

#include <array>
#include <vector>

#include "rng/fast_rng.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::policy {

inline constexpr int kNumCameras = 6;
inline constexpr const char* kCameraNames[kNumCameras] = {"CAM_FRONT",      "CAM_FRONT_RIGHT",
                                                          "CAM_FRONT_LEFT", "CAM_BACK",
                                                          "CAM_BACK_LEFT",  "CAM_BACK_RIGHT"};

// Sorted distinct camera indices. severity 0 draws nothing and returns an empty set.
std::vector<int> draw_dead_cameras(int severity, rng::NumpyRandomState& rng);
std::vector<int> draw_dead_cameras(int severity, rng::FastRng& rng);

using FrameMask = std::array<bool, kNumCameras>;  // true = camera dropped in this frame

// One frame's drops: always 6 uniforms, whatever the severity (so masks nest across severities for
// one seed).
FrameMask draw_lost_frame(int severity, rng::NumpyRandomState& rng);
FrameMask draw_lost_frame(int severity, rng::FastRng& rng);

// `frames` consecutive frames from one stream.
std::vector<FrameMask> draw_lost_frames(int severity, int frames, rng::NumpyRandomState& rng);
std::vector<FrameMask> draw_lost_frames(int severity, int frames, rng::FastRng& rng);

}  // namespace faultline::policy
