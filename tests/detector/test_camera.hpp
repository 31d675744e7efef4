// A nuScenes-like test camera for the detector tests: the dataset renderer draws a known world
// through it.
#pragma once

#include "dataset/synth_world.hpp"

namespace faultline::detector::test_support {

// Mounted at `yaw_deg` (0 = forward, + = left), 1.5 m up and ahead of the ego origin; camera axes x
// right, y down, z forward.
inline dataset::CameraModel camera(double yaw_deg) {
  constexpr double kPi = 3.14159265358979323846;
  dataset::CameraModel cam;
  const dataset::Mat3 axes{0, 0, 1, -1, 0, 0, 0, -1, 0};
  const dataset::Mat3 yaw = dataset::quat_to_matrix(dataset::yaw_quat(yaw_deg * kPi / 180));
  cam.sensor_to_ego = {dataset::mat_mul(yaw, axes), {1.5, 0.0, 1.5}};
  return cam;
}

}  // namespace faultline::detector::test_support
