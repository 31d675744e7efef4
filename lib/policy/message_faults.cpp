// Calibration drift, timestamp skew and stale frames' lag: seeded, severity-scaled, exact
// arithmetic.
#include "policy/message_faults.hpp"

#include <algorithm>
#include <cmath>

#include "rng/fast_rng.hpp"

namespace faultline::policy {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::size_t level(int severity) { return static_cast<std::size_t>(std::clamp(severity, 1, 5) - 1); }

// A unit vector uniform on the sphere (normalised Gaussian triple).
std::array<double, 3> direction(rng::FastRng& r) {
  std::array<double, 3> v{};
  double n = 0;
  while (n < 1e-9) {
    for (double& c : v) c = r.standard_normal();
    n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  }
  for (double& c : v) c /= n;
  return v;
}

using Quat = std::array<double, 4>;  // w, x, y, z

Quat multiply(const Quat& a, const Quat& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

Quat axis_angle(int axis, double rad) {
  Quat q{std::cos(rad / 2), 0, 0, 0};
  q[static_cast<std::size_t>(axis) + 1] = std::sin(rad / 2);
  return q;
}

}  // namespace

CalibrationDrift calibration_drift(int severity, std::uint64_t seed) {
  CalibrationDrift d;
  if (severity <= 0) return d;
  static constexpr double kRotDeg[] = {0.1, 0.25, 0.5, 1.0, 2.0};
  static constexpr double kShiftM[] = {0.01, 0.025, 0.05, 0.10, 0.20};
  static constexpr double kFocal[] = {0.0025, 0.005, 0.01, 0.02, 0.04};
  rng::FastRng r(seed);  // the same draws at every severity: a ramp scales one error
  const auto axis = direction(r);
  const auto shift = direction(r);
  const double sign = r.random_sample() < 0.5 ? -1.0 : 1.0;
  const double rot = kRotDeg[level(severity)] * kPi / 180.0;
  d.roll_rad = rot * axis[0];
  d.pitch_rad = rot * axis[1];
  d.yaw_rad = rot * axis[2];
  d.dx_m = kShiftM[level(severity)] * shift[0];
  d.dy_m = kShiftM[level(severity)] * shift[1];
  d.dz_m = kShiftM[level(severity)] * shift[2];
  d.focal_scale = 1.0 + sign * kFocal[level(severity)];
  return d;
}

void apply_drift(const CalibrationDrift& drift, Calibration& c) {
  const Quat dq = multiply(multiply(axis_angle(2, drift.yaw_rad), axis_angle(1, drift.pitch_rad)),
                           axis_angle(0, drift.roll_rad));
  Quat q = multiply(c.rotation_wxyz, dq);
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (n > 0) {
    for (double& v : q) v /= n;
  }
  c.rotation_wxyz = q;
  c.translation_m[0] += drift.dx_m;
  c.translation_m[1] += drift.dy_m;
  c.translation_m[2] += drift.dz_m;
  c.intrinsics[0] *= drift.focal_scale;
  c.intrinsics[4] *= drift.focal_scale;
}

DurationNs timestamp_skew_ns(int severity, std::optional<double> offset_ms) {
  if (severity <= 0) return 0;
  static constexpr double kMs[] = {5, 10, 20, 50, 100};
  const double ms = offset_ms ? *offset_ms : kMs[level(severity)];
  return static_cast<DurationNs>(std::llround(ms * 1e6));
}

DurationNs stale_frames_ns(int severity, std::optional<double> delay_ms) {
  if (severity <= 0) return 0;
  const double ms = delay_ms ? *delay_ms : kStaleFramePeriods[level(severity)] * 1000.0 / 12.0;
  return static_cast<DurationNs>(std::llround(ms * 1e6));
}

}  // namespace faultline::policy
