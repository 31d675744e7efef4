// rolling_shutter (Faultline's own, docs/faults.md "Stream and system faults"): a rolling-shutter
// CMOS reads its rows one after another over the readout time, so while the ego vehicle turns each
// row sees the scene rotated a little further: vertical edges lean. The yaw rate comes from the ego
// poses of consecutive frames of the camera (policy/fault_engine.cpp), so the skew follows the
// drive; without a yaw rate the frame is unchanged.
#pragma once

#include <opencv2/core.hpp>

namespace faultline::corruption {

// Severity 1..5: readout time (top row to bottom row) 5/10/20/33/50 ms.
double rolling_shutter_readout_ms(int severity);

// Horizontal focal length assumed when the frame carries none: 0.8 x width (about 64 degrees of
// horizontal field, nuScenes' front camera: 1266 px at 1600).
double default_focal_px(int width);

// Row y (of H) is shifted right by focal_px * tan(yaw_rate * readout * (y / (H - 1) - 0.5)) pixels:
// the middle row is the frame's stamp, rows read later see the scene turned further (yaw rate > 0:
// turning left, counter-clockwise seen from above). Linear interpolation, edge pixels replicated.
// CV_8UC3 in, same size and type out; severity 1..5 (callers check); focal_px <= 0 takes
// default_focal_px.
cv::Mat rolling_shutter(const cv::Mat& bgr, int severity, double yaw_rate_rad_s, double focal_px);

}  // namespace faultline::corruption
