// Camera Crash and Frame Lost draws shared by both RNG modes.
#include "policy/temporal_draws.hpp"

#include <algorithm>

namespace faultline::policy {
namespace {

template <typename Rng>
std::vector<int> dead_cameras(int severity, Rng& rng) {
  std::vector<int> out;
  for (int i = 0; i < severity; ++i) out.push_back(rng.choice6());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

template <typename Rng>
FrameMask lost_frame(int severity, Rng& rng) {
  const double p = severity * 1. / 6.;
  FrameMask mask{};
  for (int m = 0; m < kNumCameras; ++m) mask[static_cast<std::size_t>(m)] = rng.random_sample() < p;
  return mask;
}

template <typename Rng>
std::vector<FrameMask> lost_frames(int severity, int frames, Rng& rng) {
  std::vector<FrameMask> out;
  for (int f = 0; f < frames; ++f) out.push_back(lost_frame(severity, rng));
  return out;
}

}  // namespace

std::vector<int> draw_dead_cameras(int severity, rng::NumpyRandomState& rng) {
  return dead_cameras(severity, rng);
}
std::vector<int> draw_dead_cameras(int severity, rng::FastRng& rng) {
  return dead_cameras(severity, rng);
}
FrameMask draw_lost_frame(int severity, rng::NumpyRandomState& rng) {
  return lost_frame(severity, rng);
}
FrameMask draw_lost_frame(int severity, rng::FastRng& rng) { return lost_frame(severity, rng); }
std::vector<FrameMask> draw_lost_frames(int severity, int frames, rng::NumpyRandomState& rng) {
  return lost_frames(severity, frames, rng);
}
std::vector<FrameMask> draw_lost_frames(int severity, int frames, rng::FastRng& rng) {
  return lost_frames(severity, frames, rng);
}

}  // namespace faultline::policy
