// Detector output box (nuScenes submission conventions, global frame) and the per-class priors the
// detector uses.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "dataset/geometry.hpp"
#include "dataset/synth_palette.hpp"

namespace faultline::detector {

struct Box3d {
  int cls = 0;                               // dataset::SynthClass index
  dataset::Vec3 center{};                    // global, m
  double width = 1, length = 1, height = 1;  // m (nuScenes w, l, h)
  double yaw = 0;                            // rad, global
  double vx = 0, vy = 0;                     // m/s, global
  double score = 0;                          // [0, 1]
  std::string attribute;                     // "" or a nuScenes attribute
  bool truncated = false;                    // blob touched the image border
  const char* name() const {
    return dataset::kSynthPalette[static_cast<std::size_t>(cls)].detection_name;
  }
};

struct ClassPrior {
  double width, length, height;  // typical size, m (synth_world.cpp's ranges, centred)
  double merge_radius_m;         // two detections closer than this are one object
  bool vehicle;                  // vehicle.moving / vehicle.parked attributes
};

// Indexed by SynthClass.
constexpr std::array<ClassPrior, dataset::kSynthClassCount> kClassPriors = {{
    {1.9, 4.55, 1.65, 2.2, true},   // car
    {2.5, 7.5, 3.15, 3.5, true},    // truck
    {2.9, 11.25, 3.4, 5.0, true},   // bus
    {2.6, 10.5, 3.75, 5.0, true},   // trailer
    {2.8, 6.75, 3.2, 3.5, true},    // construction_vehicle
    {0.65, 0.7, 1.75, 0.6, false},  // pedestrian
    {0.8, 2.1, 1.5, 1.2, false},    // motorcycle
    {0.6, 1.75, 1.3, 1.1, false},   // bicycle
    {0.4, 0.4, 0.75, 0.6, false},   // traffic_cone
    {2.35, 0.5, 1.0, 1.2, false},   // barrier
}};

inline const ClassPrior& prior_of(int cls) { return kClassPriors[static_cast<std::size_t>(cls)]; }

}  // namespace faultline::detector
