// Faultline's own message faults (docs/faults.md, "Stream and system faults"): they change what a
// frame says about itself, never its pixels.
// - calibration_drift: the extrinsic rotation and translation and the focal length carried with the
// frame are
//   wrong by a fixed error, as after a knocked or thermally shifted mount (MultiCorrupt's and
//   3D_Corruptions_AD's spatial misalignment). The error's direction is drawn once per (run seed,
//   fault, camera) and its size follows the severity, so it persists across a camera's frames and a
//   ramp only scales it.
// - timestamp_skew: capture stamps offset by a fixed amount, as a camera whose clock lost its PTP
// sync, or a driver
//   that stamps on arrival instead of at exposure.
// - stale_frames: a camera's frames reach the consumer late by a fixed lag and keep their true
//   capture stamps, as behind a filling driver queue or a stalled link: a consumer fusing by stamp
//   gets old images. The stamps stay, the output time moves (the runtime's delay machinery).
// Pure arithmetic: the runtime maps it onto msgs::CameraFrame (runtime/engine_policy.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "common/clock.hpp"

namespace faultline::policy {

struct CalibrationDrift {
  double roll_rad = 0, pitch_rad = 0,
         yaw_rad = 0;                   // rotation error about the sensor's x, y, z axes
  double dx_m = 0, dy_m = 0, dz_m = 0;  // translation error, ego frame (metres)
  double focal_scale = 1;               // fx and fy are multiplied by it
};

// Severity 1..5: rotation 0.1/0.25/0.5/1/2 degrees about a random axis, translation 1/2.5/5/10/20
// cm in a random direction, focal length off by +-0.25/0.5/1/2/4 % (sign drawn). The same seed
// gives the same direction at every severity. Severity 0: no error.
CalibrationDrift calibration_drift(int severity, std::uint64_t seed);

// The calibration a camera frame carries: K (3x3 row-major, pixels), sensor -> ego rotation (w, x,
// y, z) and translation (metres), p_ego = R p_sensor + t.
struct Calibration {
  std::array<double, 9> intrinsics{};
  std::array<double, 4> rotation_wxyz{1, 0, 0, 0};
  std::array<double, 3> translation_m{};
};
// R' = R * dR (dR = Rz(yaw) Ry(pitch) Rx(roll), the error in the sensor frame), t' = t + dt, fx' =
// fx * s, fy' = fy * s; the principal point and skew are kept.
void apply_drift(const CalibrationDrift& drift, Calibration& calibration);

// Severity 1..5: the stamp offset, 5/10/20/50/100 ms later than the exposure (at 12 Hz a frame
// lasts 83 ms). `offset_ms` (a configured amount, either sign) replaces the table. Severity 0: no
// offset.
DurationNs timestamp_skew_ns(int severity, std::optional<double> offset_ms = std::nullopt);

// Severity 1..5: the lag in frame periods of a 12 Hz camera (nuScenes' rate, 83.3 ms a frame):
// 1/2/3/5/8 periods = 83.3/166.7/250/416.7/666.7 ms, rounded to the ns. `delay_ms` (a configured
// amount, >= 0) replaces the table. Severity 0: no lag.
DurationNs stale_frames_ns(int severity, std::optional<double> delay_ms = std::nullopt);
inline constexpr int kStaleFramePeriods[] = {1, 2, 3, 5, 8};

// What the message faults of one frame change; several faults on a frame add up (rotations compose,
// focal scales multiply).
struct MessageEdit {
  DurationNs stamp_offset_ns = 0;
  std::optional<CalibrationDrift> calibration;
  bool empty() const { return stamp_offset_ns == 0 && !calibration; }
};

}  // namespace faultline::policy
