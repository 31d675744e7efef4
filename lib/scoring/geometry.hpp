// Box geometry as the devkit computes it: pyquaternion rotation matrix and yaw, bike-rack point
// test, scale IoU, angle difference. Kept bit-compatible where the devkit's decisions are discrete.
#pragma once

#include <array>

#include "scoring/eval_box.hpp"

namespace faultline::scoring {

using Mat3 = std::array<std::array<double, 3>, 3>;

// pyquaternion: normalised when |1 - |q|^2| >= 1e-14 (a zero quaternion stays zero).
Mat3 rotation_matrix(const std::array<double, 4>& q);
// Heading of the rotated x-axis: atan2(R10, R00) (not 2*atan2(z, w)).
double quaternion_yaw(const std::array<double, 4>& q);
// devkit points_in_box for one point: inclusive along the rack's three edges.
bool point_in_box(const RackBox& box, const std::array<double, 3>& p);
// 1 - aligned 3D IoU of the two sizes; both must be > 0.
double scale_iou(const std::array<double, 3>& gt_size, const std::array<double, 3>& pred_size);
// |angle difference| wrapped with the given period (2*pi, or pi for barriers).
double angle_diff(double gt_yaw, double pred_yaw, double period);

}  // namespace faultline::scoring
