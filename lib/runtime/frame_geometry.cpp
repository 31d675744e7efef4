// Quaternions of the frame header to the camera's rotation in the world.
#include "runtime/frame_geometry.hpp"

#include <cmath>

namespace faultline::runtime {
namespace {

// Rotation of a unit quaternion (w, x, y, z); none for a zero or non-finite one.
std::optional<cv::Matx33d> rotation(const msgs::Quaternion& q) {
  const double n = std::sqrt(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z());
  if (!(n > 1e-9) || !std::isfinite(n)) return std::nullopt;
  const double w = q.w() / n, x = q.x() / n, y = q.y() / n, z = q.z() / n;
  return cv::Matx33d(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                     2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                     2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y));
}

}  // namespace

std::optional<corruption::CameraGeometry> frame_geometry(const msgs::CameraFrame& frame) {
  if (!frame.has_ego_pose() || !frame.has_sensor_to_ego()) return std::nullopt;
  const auto ego = rotation(frame.ego_pose().rotation());
  const auto sensor = rotation(frame.sensor_to_ego().rotation());
  if (!ego || !sensor) return std::nullopt;
  corruption::CameraGeometry g;
  g.camera_to_world = *ego * *sensor;
  if (frame.intrinsics_size() == 9) {
    cv::Matx33d k;
    for (int i = 0; i < 9; ++i) k.val[i] = frame.intrinsics(i);
    if (k(0, 0) > 0 && k(1, 1) > 0 && std::isfinite(k(0, 2)) && std::isfinite(k(1, 2)))
      g.intrinsics = k;
  }
  return g;
}

}  // namespace faultline::runtime
