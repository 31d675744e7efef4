// Faultline's own sensor faults (none of the references has them): lens soiling, water drops on the
// lens, sun glare / lens flare and exposure flicker. Each is a model drawn once from a seed (the
// dirt, the drops, the light source, the flicker's frequencies and phases) and rendered per frame,
// so a camera keeps the same fault while its cause persists (docs/faults.md "Sensor faults"). Pure:
// no I/O, no clocks, no globals.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>

#include "common/status.hpp"
#include "corruption/types.hpp"

namespace faultline::corruption {

// Where the camera looks: the rotation from camera axes (x right, y down, z forward, as nuScenes'
// cameras) to the world, and the pinhole intrinsics K in pixels when known.
struct CameraGeometry {
  cv::Matx33d camera_to_world = cv::Matx33d::eye();
  std::optional<cv::Matx33d> intrinsics;
};

// What a frame tells a sensor fault besides its pixels.
struct FrameContext {
  std::optional<double>
      time_s;  // capture time (s, any fixed origin); none: frame index / kDefaultRateHz
  std::optional<CameraGeometry> geometry;  // none: the glare source stays where it was drawn
};

// The frame rate assumed for time when frames carry no time (nuScenes' cameras run at 12 Hz).
inline constexpr double kDefaultRateHz = 12.0;

// Soiling, WaterDrops, Glare, ExposureFlicker.
bool is_sensor_fault(Corruption c);

// One camera's sensor fault: the model is drawn from `seed` on the first frame (and again when the
// frame size changes); every later frame renders the same model at its own time and pose. Not
// thread-safe; one per camera.
class SensorFaultState {
 public:
  SensorFaultState(Corruption type, int severity, std::uint64_t seed);
  ~SensorFaultState();
  SensorFaultState(const SensorFaultState&) = delete;
  SensorFaultState& operator=(const SensorFaultState&) = delete;

  // `frame_index` counts this camera's frames from 0 (the time when ctx has none). Input CV_8UC3,
  // severity >= 1.
  Result<cv::Mat> apply(const cv::Mat& bgr, std::int64_t frame_index, const FrameContext& ctx);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One frame on its own (faultline corrupt, export): the model drawn from `seed` rendered at ctx's
// time (0 if none).
Result<cv::Mat> sensor_fault(const cv::Mat& bgr, Corruption type, int severity, std::uint64_t seed,
                             const FrameContext& ctx = {});

}  // namespace faultline::corruption
