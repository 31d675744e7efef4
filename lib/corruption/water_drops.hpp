// Water drops on the lens (Faultline's own). A drop on the front glass is a small, thick lens far
// out of focus: it shows a blurred, inverted and wider view of the scene around it, darkened
// towards its rim where light leaves at steep angles. Drops sit still while small; larger ones
// slide down slowly, and drops that touch merge into one of their summed area. New drops arrive at
// the severity's rain rate; drops that slide off the bottom are gone. The drops are drawn from the
// seed; a camera's state moves them by each frame's time step (at most 1 s, none when time goes
// backwards), drawing the arrivals from the model's own stream, so a seed and the frame times
// reproduce the sequence.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "rng/fast_rng.hpp"

namespace faultline::corruption {

struct WaterDropsParams {
  int drops;          // drops on the lens at the start
  double min_radius;  // drop radius range, share of the image height
  double max_radius;
  double rain_per_s;  // new drops per second
};
// Severity 1..5: drizzle (6 drops of 1.5-3 % of the height, 0.2 new per second) up to heavy rain
// (50 drops of 3-8 %, 4 per second); docs/faults.md lists the table.
WaterDropsParams water_drops_params(int severity);

struct Drop {
  double x, y;  // centre (px)
  double r;     // radius (px)
  double vx;    // sideways drift as a share of the sliding speed (-0.2..0.2)
};

class WaterDropsModel {
 public:
  WaterDropsModel(int severity, std::uint64_t seed, cv::Size size);

  // Advances the drops by dt seconds (clamped to [0, 1]): slide, merge, leave, arrive.
  void step(double dt_s);
  // The frame seen through the drops. CV_8UC3 of the model's size.
  cv::Mat apply(const cv::Mat& bgr) const;

  const std::vector<Drop>& drops() const { return drops_; }
  void set_drops(
      std::vector<Drop> drops);  // replaces the drops (tests, replays); merges any that touch
  cv::Size size() const { return size_; }

 private:
  Drop new_drop();
  void merge();

  WaterDropsParams params_;
  cv::Size size_;
  rng::FastRng rng_;
  std::vector<Drop> drops_;
};

}  // namespace faultline::corruption
