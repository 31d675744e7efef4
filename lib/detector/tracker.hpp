// Multi-object tracker over per-camera detections at the full camera rate (~12 Hz per camera):
// greedy nearest association per class, position and velocity from a least-squares line fit over
// the last second of measurements, yaw from the motion direction for moving objects, coasting
// through a few missed frames.
#pragma once

#include <cstdint>
#include <deque>
#include <vector>

#include "detector/box.hpp"
#include "detector/lift.hpp"

namespace faultline::detector {

struct TrackerConfig {
  double history_s = 1.0;  // measurement window of the line fit
  double coast_s = 0.45;   // a track unseen for longer is not reported (about 5 frames at 12 Hz)
  double delete_s = 1.0;   // ... and deleted after this long
  double gate_m = 1.5;     // association gate on top of the class merge radius
  double moving_speed_mps = 1.0;  // faster tracks take their yaw from the motion direction
};

class Tracker {
 public:
  explicit Tracker(const TrackerConfig& config = {}) : config_(config) {}
  // Detections of one camera frame captured at `t_us`.
  void update(const std::vector<Box3d>& detections, std::int64_t t_us);
  // Tracks alive at `t_us`, predicted to that time; road prior for slow objects' yaw and
  // attributes.
  std::vector<Box3d> report(std::int64_t t_us, const dataset::Rigid& ego_to_world,
                            const RoadPrior& road) const;
  std::size_t size() const { return tracks_.size(); }

 private:
  struct Measurement {
    double t_s, x, y, score;
  };
  struct Track {
    Box3d box;  // latest detection (class, size, score)
    std::deque<Measurement> history;
    int hits = 0;
    double last_s = 0;
  };
  // Position and velocity of the fit, evaluated at t_s.
  static void fit(const Track& tr, double t_s, double* x, double* y, double* vx, double* vy);

  TrackerConfig config_;
  std::vector<Track> tracks_;
};

}  // namespace faultline::detector
