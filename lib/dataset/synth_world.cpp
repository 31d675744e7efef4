// Scene model for the synthetic dataset: road geometry, ego trajectory and actor placement.
#include "dataset/synth_world.hpp"

#include <algorithm>
#include <cmath>

namespace faultline::dataset {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kLaneWidth = 3.5;

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

bool chance(std::mt19937_64& rng, double p) { return uniform(rng, 0, 1) < p; }

Actor sized(SynthClass cls, std::mt19937_64& rng) {
  Actor a;
  a.cls = cls;
  switch (cls) {
    case SynthClass::kCar:
      a.width = uniform(rng, 1.8, 2.0);
      a.length = uniform(rng, 4.2, 4.9);
      a.height = uniform(rng, 1.5, 1.8);
      break;
    case SynthClass::kTruck:
      a.width = 2.5;
      a.length = uniform(rng, 6.5, 8.5);
      a.height = uniform(rng, 2.9, 3.4);
      break;
    case SynthClass::kBus:
      a.width = 2.9;
      a.length = uniform(rng, 10.5, 12.0);
      a.height = 3.4;
      break;
    case SynthClass::kPedestrian:
      a.width = uniform(rng, 0.6, 0.7);
      a.length = uniform(rng, 0.6, 0.8);
      a.height = uniform(rng, 1.6, 1.9);
      break;
    case SynthClass::kMotorcycle:
      a.width = 0.8;
      a.length = uniform(rng, 2.0, 2.2);
      a.height = 1.5;
      break;
    case SynthClass::kBicycle:
      a.width = 0.6;
      a.length = uniform(rng, 1.7, 1.8);
      a.height = 1.3;
      break;
    case SynthClass::kTrafficCone:
      a.width = 0.4;
      a.length = 0.4;
      a.height = uniform(rng, 0.7, 0.8);
      break;
    case SynthClass::kBarrier:
      a.width = uniform(rng, 2.2, 2.5);
      a.length = 0.5;
      a.height = 1.0;
      break;
    case SynthClass::kTrailer:
      a.width = 2.6;
      a.length = uniform(rng, 9, 12);
      a.height = uniform(rng, 3.5, 4.0);
      break;
    case SynthClass::kConstructionVehicle:
      a.width = 2.8;
      a.length = uniform(rng, 6, 7.5);
      a.height = 3.2;
      break;
  }
  return a;
}

// Fills one lane with vehicles moving at the lane speed (so they never collide), spaced over [s_lo,
// s_hi].
void fill_lane(std::mt19937_64& rng, std::vector<Actor>* out, double d, double speed, double s_lo,
               double s_hi) {
  double s = s_lo + uniform(rng, 0, 20);
  while (s < s_hi) {
    const double r = uniform(rng, 0, 1);
    const SynthClass cls = r < 0.72   ? SynthClass::kCar
                           : r < 0.82 ? SynthClass::kTruck
                           : r < 0.90 ? SynthClass::kBus
                                      : SynthClass::kMotorcycle;
    Actor a = sized(cls, rng);
    a.motion = Motion::kMoving;
    a.d = d;
    a.speed = speed;
    a.s0 = s + a.length / 2;
    a.yaw_offset = speed < 0 ? kPi : 0;
    out->push_back(a);
    s += a.length + uniform(rng, 10, 35);
  }
}

}  // namespace

Vec3 Road::point(double s, double d) const {
  double x = 0, y = 0;
  if (std::abs(curvature) < 1e-9) {
    x = x0 + s * std::cos(heading0);
    y = y0 + s * std::sin(heading0);
  } else {
    const double h = heading(s);
    x = x0 + (std::sin(h) - std::sin(heading0)) / curvature;
    y = y0 - (std::cos(h) - std::cos(heading0)) / curvature;
  }
  const double h = heading(s);
  return {x - d * std::sin(h), y + d * std::cos(h), 0.0};
}

double SynthWorld::ego_s(double t) const { return ego_speed * t + 0.5 * ego_accel * t * t; }

Rigid SynthWorld::ego_pose(double t) const {
  const double s = ego_s(t);
  return make_rigid(yaw_quat(road.heading(s)), road.point(s, ego_lane_d));
}

ActorState SynthWorld::actor_state(const Actor& a, double t) const {
  const double s = a.s0 + a.speed * t;
  Vec3 c = road.point(s, a.d);
  c[2] = a.height / 2;
  return {c, road.heading(s) + a.yaw_offset};
}

SynthWorld make_world(std::mt19937_64& rng, double duration_s) {
  SynthWorld w;
  w.road.x0 = uniform(rng, 300, 1800);
  w.road.y0 = uniform(rng, 300, 1800);
  w.road.heading0 = uniform(rng, -kPi, kPi);
  w.road.curvature = chance(rng, 0.5) ? 0.0 : uniform(rng, -0.004, 0.004);
  w.ego_speed = uniform(rng, 5, 11);
  // Keeps the ego behind its lead car and ahead of its follower for the whole scene (see fill-in
  // below).
  w.ego_accel = uniform(rng, -0.15, 0.05) * std::min(1.0, 20.0 / std::max(duration_s, 1.0));
  w.ego_lane_d = -kLaneWidth / 2;

  const double travel = w.ego_s(duration_s);
  const double s_lo = -70, s_hi = travel + 90;
  auto& a = w.actors;

  // Ego lane: a lead vehicle pulling away slowly and a slower follower.
  Actor lead = sized(SynthClass::kCar, rng);
  lead.motion = Motion::kMoving;
  lead.d = w.ego_lane_d;
  lead.s0 = uniform(rng, 18, 28);
  lead.speed = w.ego_speed + 0.5;
  a.push_back(lead);
  Actor follower = sized(chance(rng, 0.7) ? SynthClass::kCar : SynthClass::kMotorcycle, rng);
  follower.motion = Motion::kMoving;
  follower.d = w.ego_lane_d;
  follower.s0 = -uniform(rng, 16, 24);
  follower.speed = w.ego_speed - 1.5;
  a.push_back(follower);

  // Other lanes: same-direction outer lane and two oncoming lanes; the spawn range covers
  // everything that passes.
  const double same_speed = w.ego_speed + uniform(rng, -1.5, 2.5);
  fill_lane(rng, &a, -1.5 * kLaneWidth, same_speed, s_lo - same_speed * duration_s, s_hi);
  for (double d : {0.5 * kLaneWidth, 1.5 * kLaneWidth}) {
    const double v = -uniform(rng, 7, 13);
    fill_lane(rng, &a, d, v, s_lo, s_hi - v * duration_s);
  }

  // Parked vehicles on the left parking strip: mostly cars, some trucks, trailers and construction
  // vehicles.
  for (double s = s_lo; s < s_hi; s += uniform(rng, 6.5, 9)) {
    if (!chance(rng, 0.55)) continue;
    const double r = uniform(rng, 0, 1);
    Actor p = sized(r < 0.76   ? SynthClass::kCar
                    : r < 0.84 ? SynthClass::kTruck
                    : r < 0.92 ? SynthClass::kTrailer
                               : SynthClass::kConstructionVehicle,
                    rng);
    p.motion = Motion::kParked;
    p.d = 8.5;
    p.s0 = s;
    p.yaw_offset = (chance(rng, 0.5) ? 0 : kPi) + uniform(rng, -0.05, 0.05);
    a.push_back(p);
    s += p.length;
  }

  // Pedestrians on both sidewalks, walking either way or standing.
  for (double s = s_lo; s < s_hi; s += uniform(rng, 6, 18)) {
    Actor p = sized(SynthClass::kPedestrian, rng);
    const bool left = chance(rng, 0.5);
    p.d = (left ? 1 : -1) * uniform(rng, 10.7, 12.3);
    p.s0 = s;
    if (chance(rng, 0.65)) {
      p.motion = Motion::kMoving;
      p.speed = (chance(rng, 0.5) ? 1 : -1) * uniform(rng, 1.0, 1.6);
      p.yaw_offset = p.speed < 0 ? kPi : 0;
    } else {
      p.motion = Motion::kStanding;
      p.yaw_offset = uniform(rng, -kPi, kPi);
    }
    a.push_back(p);
  }

  // Cyclists in the right bike lane.
  for (double s = s_lo - 5 * duration_s; s < s_hi; s += uniform(rng, 50, 110)) {
    Actor b = sized(chance(rng, 0.75) ? SynthClass::kBicycle : SynthClass::kMotorcycle, rng);
    b.motion = Motion::kMoving;
    b.d = -8.5;
    b.s0 = s;
    b.speed = b.cls == SynthClass::kBicycle ? uniform(rng, 3.5, 5.5) : uniform(rng, 6, 9);
    a.push_back(b);
  }

  // Cone lines and barrier rows on the right shoulder, static.
  for (double s = s_lo + uniform(rng, 0, 40); s < s_hi; s += uniform(rng, 45, 90)) {
    const bool cones = chance(rng, 0.55);
    const int n =
        cones ? 4 + static_cast<int>(uniform(rng, 0, 3)) : 3 + static_cast<int>(uniform(rng, 0, 2));
    for (int i = 0; i < n; ++i) {
      Actor c = sized(cones ? SynthClass::kTrafficCone : SynthClass::kBarrier, rng);
      c.motion = Motion::kStatic;
      c.d = -9.4;
      c.s0 = s + i * (cones ? 2.0 : 2.6);
      c.yaw_offset = cones ? uniform(rng, -kPi, kPi)
                           : kPi / 2;  // barriers run along the road (their width axis)
      a.push_back(c);
    }
    s += n * 2.6;
  }
  return w;
}

}  // namespace faultline::dataset
