// The 3D scene model behind the synthetic dataset: a straight or gently curved road (lanes, parking
// strip, sidewalks), an ego vehicle driving in its lane, and actors of several classes moving along
// lanes or standing. Everything is a pure function of the scene seed and the time, so images and
// tables agree exactly.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "dataset/geometry.hpp"
#include "dataset/synth_palette.hpp"

namespace faultline::dataset {

// Road centreline: arc length s (m) -> world xy and heading; d (m) is the lateral offset, positive
// to the left.
struct Road {
  double x0 = 0, y0 = 0, heading0 = 0;   // world position/heading at s = 0
  double curvature = 0;                  // 1/m; 0 = straight
  Vec3 point(double s, double d) const;  // z = 0
  double heading(double s) const { return heading0 + curvature * s; }
};

enum class Motion { kMoving, kParked, kStanding, kStatic };

struct Actor {
  SynthClass cls = SynthClass::kCar;
  Motion motion = Motion::kStatic;
  double width = 1, length = 1, height = 1;  // m (nuScenes size order w, l, h)
  double s0 = 0, d = 0;                      // road coordinates at t = 0
  double speed = 0;                          // m/s along s (negative = oncoming)
  double yaw_offset = 0;                     // rad, added to the road heading
};

struct ActorState {
  Vec3 center;  // box centre, world frame (bottom on the ground)
  double yaw = 0;
};

struct SynthWorld {
  Road road;
  double ego_speed = 8, ego_accel = 0;  // m/s, m/s^2 along the ego lane
  double ego_lane_d = -1.75;
  std::vector<Actor> actors;

  double ego_s(double t) const;
  Rigid ego_pose(double t) const;  // ego -> world at t seconds after scene start
  ActorState actor_state(const Actor& a, double t) const;
};

// Builds one scene's world for `duration_s` seconds from the given engine state.
SynthWorld make_world(std::mt19937_64& rng, double duration_s);

}  // namespace faultline::dataset
