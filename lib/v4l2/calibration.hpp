// Camera calibration for live cameras, from a YAML file, so the injector, detector and sink treat a
// V4L2 camera like a nuScenes one. Accepts the nuScenes-style keys (intrinsics 3x3 row-major,
// sensor_to_ego {translation, rotation wxyz}) or a ROS camera_info file (camera_matrix.data).
#pragma once

#include <array>
#include <string>

namespace faultline::v4l2 {

struct Calibration {
  std::string channel = "CAM_FRONT";
  std::uint32_t width = 0, height = 0;         // 0 = not stated
  std::array<double, 9> intrinsics{};          // K, row-major
  std::array<double, 3> translation{};         // sensor origin in the ego frame (m)
  std::array<double, 4> rotation{1, 0, 0, 0};  // sensor -> ego, w x y z
};

// Throws ConfigError naming the file, key and value on a problem.
Calibration load_calibration(const std::string& path);

}  // namespace faultline::v4l2
