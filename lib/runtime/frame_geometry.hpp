// The camera geometry a CameraFrame carries (ego pose, calibrated sensor, intrinsics) as the sensor
// faults take it.
#pragma once

#include <optional>

#include "camera_frame.pb.h"
#include "corruption/sensor_fault.hpp"

namespace faultline::runtime {

// camera -> world rotation = ego_pose x sensor_to_ego (nuScenes conventions), and K when the frame
// has all nine values. None when the frame has no ego pose or calibration, or a zero quaternion
// (not set by the source).
std::optional<corruption::CameraGeometry> frame_geometry(const msgs::CameraFrame& frame);

}  // namespace faultline::runtime
