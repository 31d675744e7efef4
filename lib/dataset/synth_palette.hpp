// Class -> body colour of the synthetic dataset renderer. Each detection class has its own hue
// (hues >= 25 degrees apart) so a pixel-only reference detector can classify a blob by colour and
// its projected size by class. Faces are shaded by a fixed world light: rendered colour = body_bgr
// * (kAmbient + kDiffuse * max(0, n . L)), so the hue (ratios between channels) is kept while
// brightness varies between 0.40x (unlit side) and ~0.95x (top).
//
// | class                | nuScenes category           | BGR             | hue   | typical size w x
// l x h (m) |
// |----------------------|-----------------------------|-----------------|-------|----------------------------|
// | car                  | vehicle.car                 | ( 30,  30, 220) | 0     | 1.9 x 4.6 x 1.7
// | | truck                | vehicle.truck               | (  0, 120, 255) | 28    | 2.5 x 7.5
// x 3.2            | | bus                  | vehicle.bus.rigid           | (  0, 230, 230) | 60
// | 2.9 x 11.5 x 3.4           | | trailer              | vehicle.trailer             | (  0, 230,
// 128) | 90    | 2.6 x 10.5 x 3.75 (parked) | | construction_vehicle | vehicle.construction | ( 60,
// 180,   0) | 130   | 2.8 x 6.8 x 3.2 (parked)   | | pedestrian           | human.pedestrian.adult
// | (255,   0, 255) | 300   | 0.65 x 0.7 x 1.75          | | motorcycle           |
// vehicle.motorcycle          | (255,  90,   0) | 219   | 0.8 x 2.1 x 1.5            | | bicycle |
// vehicle.bicycle             | (230, 230,   0) | 180   | 0.6 x 1.75 x 1.3           | |
// traffic_cone         | movable_object.trafficcone  | (140,  40, 255) | 337   | 0.4 x 0.4 x 0.75 |
// | barrier              | movable_object.barrier      | (255,   0, 140) | 273   | 2.3 x 0.5 x 1.0
// |
//
// Scenery is grey or low-saturation so it never matches a class: sky (235, 215, 195), ground (95,
// 110, 120), asphalt (70, 70, 70), sidewalk (160, 165, 170), lane marks (235, 235, 235).
#pragma once

#include <array>
#include <cstdint>

namespace faultline::dataset {

enum class SynthClass {
  kCar,
  kTruck,
  kBus,
  kTrailer,
  kConstructionVehicle,
  kPedestrian,
  kMotorcycle,
  kBicycle,
  kTrafficCone,
  kBarrier
};
constexpr int kSynthClassCount = 10;

using Bgr = std::array<std::uint8_t, 3>;

struct SynthClassStyle {
  const char* detection_name;  // nuScenes detection class
  const char* category;        // nuScenes category name written to the tables
  Bgr body_bgr;                // unshaded body colour
};

// Indexed by SynthClass; order = the devkit's detection class order.
constexpr std::array<SynthClassStyle, kSynthClassCount> kSynthPalette = {{
    {"car", "vehicle.car", {30, 30, 220}},
    {"truck", "vehicle.truck", {0, 120, 255}},
    {"bus", "vehicle.bus.rigid", {0, 230, 230}},
    {"trailer", "vehicle.trailer", {0, 230, 128}},
    {"construction_vehicle", "vehicle.construction", {60, 180, 0}},
    {"pedestrian", "human.pedestrian.adult", {255, 0, 255}},
    {"motorcycle", "vehicle.motorcycle", {255, 90, 0}},
    {"bicycle", "vehicle.bicycle", {230, 230, 0}},
    {"traffic_cone", "movable_object.trafficcone", {140, 40, 255}},
    {"barrier", "movable_object.barrier", {255, 0, 140}},
}};

inline const SynthClassStyle& style_of(SynthClass c) { return kSynthPalette[static_cast<int>(c)]; }

constexpr Bgr kSkyBgr = {235, 215, 195};
constexpr Bgr kGroundBgr = {95, 110, 120};
constexpr Bgr kAsphaltBgr = {70, 70, 70};
constexpr Bgr kSidewalkBgr = {160, 165, 170};
constexpr Bgr kLaneMarkBgr = {235, 235, 235};

// Shading: light direction in the world frame (normalised at use), ambient and diffuse weights.
constexpr std::array<double, 3> kLightDirection = {0.35, 0.25, 0.9};
constexpr double kAmbient = 0.40;
constexpr double kDiffuse = 0.60;

}  // namespace faultline::dataset
