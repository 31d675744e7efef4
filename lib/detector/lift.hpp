// Lifts a 2D blob to a 3D box: the ray through the blob's bottom-centre pixel meets the ground
// plane (z = 0, global) at the object's near edge; the centre lies half the prior extent further
// along the viewing direction. When the bottom edge is hidden (image border or an occluder in
// front) the top edge meets the plane z = height.
#pragma once

#include <array>
#include <optional>

#include "dataset/geometry.hpp"
#include "detector/blobs.hpp"
#include "detector/box.hpp"

namespace faultline::detector {

struct CameraGeometry {
  std::array<double, 9> intrinsics{};  // K row-major, for the full-resolution image
  dataset::Rigid sensor_to_ego;
  dataset::Rigid ego_to_world;
  int width = 1600, height = 900;  // full-resolution image size
};

struct LiftConfig {
  double max_range_m = 65;  // farther blobs are dropped (the metric evaluates up to 50 m)
};

// Road frame: heading of the road at the ego and its curvature (1/m, + = turning left), for the yaw
// prior.
struct RoadPrior {
  double ego_yaw = 0;
  double curvature = 0;
};

// The box (global) or nullopt when the ray misses the plane or the object is out of range.
std::optional<Box3d> lift_blob(const Blob& blob, const CameraGeometry& cam, const RoadPrior& road,
                               const LiftConfig& config = {});

// Yaw and attribute from the road layout at a global position (used when motion is unknown):
// vehicles in the oncoming lanes face against the ego, everything else with it; parked strip =
// vehicle.parked.
void apply_layout_prior(Box3d* box, const dataset::Rigid& ego_to_world, const RoadPrior& road);

}  // namespace faultline::detector
