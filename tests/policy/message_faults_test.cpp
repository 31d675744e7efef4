// calibration_drift and timestamp_skew: exact values per severity, the drift's persistence per
// camera, the arithmetic applied to a calibration, and what the engine and the schedule parser make
// of them; rolling_shutter's yaw rate from the ego poses of one camera's frames.
#include "policy/message_faults.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "common/config.hpp"
#include "corruption/rolling_shutter.hpp"
#include "policy/fault_engine.hpp"
#include "policy/seeding.hpp"

namespace faultline::policy {
namespace {

// Member by member: FrameInfo's optional pose fields stay unset.
FrameInfo Info(const std::string& camera, std::uint64_t seq, StampNs stamp) {
  FrameInfo f;
  f.camera = camera;
  f.source_seq = seq;
  f.capture_stamp_ns = stamp;
  return f;
}

constexpr double kPi = 3.14159265358979323846;
constexpr StampNs kT0 = 1'600'000'000'000'000'000;

double RotationDeg(const CalibrationDrift& d) {
  return std::sqrt(d.roll_rad * d.roll_rad + d.pitch_rad * d.pitch_rad + d.yaw_rad * d.yaw_rad) *
         180 / kPi;
}
double ShiftM(const CalibrationDrift& d) {
  return std::sqrt(d.dx_m * d.dx_m + d.dy_m * d.dy_m + d.dz_m * d.dz_m);
}

TEST(CalibrationDriftTest, SeverityScalesOneSeededError) {
  const double rot[] = {0.1, 0.25, 0.5, 1.0, 2.0}, shift[] = {0.01, 0.025, 0.05, 0.10, 0.20},
               focal[] = {0.0025, 0.005, 0.01, 0.02, 0.04};
  const CalibrationDrift one = calibration_drift(1, 42);
  for (int sev = 1; sev <= 5; ++sev) {
    const CalibrationDrift d = calibration_drift(sev, 42);
    EXPECT_NEAR(RotationDeg(d), rot[sev - 1], 1e-12);
    EXPECT_NEAR(ShiftM(d), shift[sev - 1], 1e-12);
    EXPECT_NEAR(std::abs(d.focal_scale - 1), focal[sev - 1], 1e-15);
    // The same direction at every severity: a ramp grows one error.
    EXPECT_NEAR(d.yaw_rad / rot[sev - 1], one.yaw_rad / rot[0], 1e-12);
    EXPECT_NEAR(d.dx_m / shift[sev - 1], one.dx_m / shift[0], 1e-12);
    EXPECT_EQ(d.focal_scale > 1, one.focal_scale > 1);
    EXPECT_FALSE(std::isnan(d.roll_rad + d.pitch_rad + d.yaw_rad + d.dx_m + d.dy_m + d.dz_m +
                            d.focal_scale));
  }
  const CalibrationDrift again = calibration_drift(3, 42), other = calibration_drift(3, 43);
  EXPECT_EQ(again.yaw_rad, calibration_drift(3, 42).yaw_rad);
  EXPECT_NE(again.yaw_rad, other.yaw_rad);
  const CalibrationDrift off = calibration_drift(0, 42);
  EXPECT_EQ(off.yaw_rad, 0.0);
  EXPECT_EQ(off.dx_m, 0.0);
  EXPECT_EQ(off.focal_scale, 1.0);
}

TEST(CalibrationDriftTest, AppliesToTheCalibrationExactly) {
  Calibration c;
  c.intrinsics = {1266.4, 0, 816.3, 0, 1266.4, 491.5, 0, 0, 1};
  c.rotation_wxyz = {1, 0, 0, 0};
  c.translation_m = {1.70, 0.02, 1.51};
  CalibrationDrift d;
  d.yaw_rad = 0.1;
  d.dx_m = 0.05;
  d.dz_m = -0.02;
  d.focal_scale = 1.01;
  apply_drift(d, c);
  EXPECT_DOUBLE_EQ(c.intrinsics[0], 1266.4 * 1.01);
  EXPECT_DOUBLE_EQ(c.intrinsics[4], 1266.4 * 1.01);
  EXPECT_EQ(c.intrinsics[2], 816.3);  // principal point kept
  EXPECT_EQ(c.intrinsics[5], 491.5);
  EXPECT_EQ(c.intrinsics[8], 1.0);
  EXPECT_NEAR(c.rotation_wxyz[0], std::cos(0.05), 1e-15);
  EXPECT_NEAR(c.rotation_wxyz[3], std::sin(0.05), 1e-15);
  EXPECT_EQ(c.rotation_wxyz[1], 0.0);
  EXPECT_EQ(c.rotation_wxyz[2], 0.0);
  EXPECT_DOUBLE_EQ(c.translation_m[0], 1.75);
  EXPECT_DOUBLE_EQ(c.translation_m[1], 0.02);
  EXPECT_DOUBLE_EQ(c.translation_m[2], 1.49);
  // No drift: the calibration is unchanged.
  Calibration e = c;
  apply_drift(CalibrationDrift{}, e);
  EXPECT_EQ(e.intrinsics, c.intrinsics);
  EXPECT_EQ(e.rotation_wxyz, c.rotation_wxyz);
  EXPECT_EQ(e.translation_m, c.translation_m);
}

TEST(TimestampSkewTest, OffsetsPerSeverityAndConfigured) {
  const DurationNs expected[] = {5'000'000, 10'000'000, 20'000'000, 50'000'000, 100'000'000};
  for (int sev = 1; sev <= 5; ++sev) EXPECT_EQ(timestamp_skew_ns(sev), expected[sev - 1]);
  EXPECT_EQ(timestamp_skew_ns(0), 0);
  EXPECT_EQ(timestamp_skew_ns(3, -33.5), -33'500'000);
  EXPECT_EQ(timestamp_skew_ns(0, -33.5), 0) << "off outside the window";
}

TEST(MessageFaultEngineTest, DriftPersistsPerCameraAndSkewHitsOnlyItsCameras) {
  FaultEngine engine({parse_faults(YAML::Load(R"([
      {type: calibration_drift, severity: 4, cameras: [CAM_FRONT, CAM_BACK]},
      {type: timestamp_skew, severity: 2, cameras: CAM_FRONT, start_s: 0.2},
      {type: timestamp_skew, offset_ms: -7, cameras: CAM_FRONT}])"),
                                   "test"),
                      9});
  std::optional<CalibrationDrift> front, back;
  for (int k = 0; k < 6; ++k) {
    for (int cam = 0; cam < kNumCameras; ++cam) {
      const FramePlan p = engine.decide(
          Info(kCameraNames[cam], static_cast<std::uint64_t>(k + 1), kT0 + k * 100'000'000));
      EXPECT_EQ(p.action, Action::Pass);
      EXPECT_FALSE(p.needs_pixels());
      if (cam != 0 && cam != 3) {
        EXPECT_TRUE(p.edit.empty()) << "camera " << cam;
        continue;
      }
      ASSERT_TRUE(p.edit.calibration.has_value());
      auto& first = cam == 0 ? front : back;
      if (!first) first = p.edit.calibration;
      EXPECT_EQ(p.edit.calibration->yaw_rad, first->yaw_rad) << "the drift persists, frame " << k;
      EXPECT_EQ(p.edit.calibration->dx_m, first->dx_m);
      EXPECT_EQ(p.edit.calibration->focal_scale, first->focal_scale);
      const CalibrationDrift want = calibration_drift(4, p.faults[0].seed);
      EXPECT_EQ(p.edit.calibration->pitch_rad, want.pitch_rad);
      EXPECT_EQ(p.faults[0].params.at("focal_scale"), want.focal_scale);
      if (cam == 0) {
        EXPECT_EQ(p.edit.stamp_offset_ns, (k >= 2 ? 10'000'000 : 0) - 7'000'000) << "frame " << k;
      }
      if (cam == 3) {
        EXPECT_EQ(p.edit.stamp_offset_ns, 0);
      }
    }
  }
  EXPECT_NE(front->yaw_rad, back->yaw_rad) << "cameras drift independently";
}

TEST(MessageFaultSpecTest, ParsesAndRefusesOffsets) {
  const auto faults = parse_faults(
      YAML::Load("[{type: timestamp_skew, offset_ms: -12.5}, {type: calibration_drift}]"), "test");
  ASSERT_EQ(faults.size(), 2u);
  EXPECT_EQ(faults[0].kind, FaultKind::TimestampSkew);
  EXPECT_EQ(*faults[0].offset_ms, -12.5);
  EXPECT_EQ(faults[1].kind, FaultKind::CalibrationDrift);
  EXPECT_EQ(faults[1].severity, 4) << "level mid as camera_crash";
  EXPECT_EQ(faults[1].name(), "calibration_drift");
  try {
    parse_faults(YAML::Load("[{type: fog, offset_ms: 3}]"), "test");
    FAIL() << "offset_ms on fog must be refused";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "test: faults[0].offset_ms = 3: only timestamp_skew takes offset_ms"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(parse_faults(YAML::Load("[{type: timestamp_skew, offset_ms: .nan}]"), "test"),
               ConfigError);
  EXPECT_TRUE(parse_corruption_shorthand("calibration_drift/5", "test").has_value());
}

// The yaw rate comes from the previous frame of the same camera (heading wrapped across +-pi); the
// first frame, and frames without a pose, pass unchanged and say so.
TEST(RollingShutterEngineTest, YawRateFromConsecutivePosesOfOneCamera) {
  FaultEngine engine(
      {parse_faults(
           YAML::Load("[{type: rolling_shutter, severity: 4, cameras: [CAM_FRONT, CAM_BACK]}]"),
           "test"),
       5});
  auto frame = [](int cam, std::uint64_t seq, double t_s, std::optional<double> yaw) {
    FrameInfo f = Info(kCameraNames[cam], seq, kT0 + static_cast<StampNs>(t_s * 1e9));
    f.ego_yaw_rad = yaw;
    f.focal_px = 100;
    return f;
  };
  const cv::Mat image = [] {
    cv::Mat m(40, 64, CV_8UC3);
    cv::randu(m, cv::Scalar::all(0), cv::Scalar::all(255));
    return m;
  }();
  FramePlan first = engine.decide(frame(0, 1, 0.0, 3.1));
  EXPECT_TRUE(first.corruptions.empty()) << "no yaw rate: no pixel work";
  EXPECT_EQ(first.action, Action::Pass);
  EXPECT_EQ(first.faults[0].params.at("no_yaw_rate"), 1.0);
  cv::Mat unchanged = image.clone();
  ASSERT_TRUE(engine.render(first, unchanged).is_ok());
  EXPECT_EQ(cv::norm(unchanged, image, cv::NORM_INF), 0.0);
  // Another camera's pose in between does not count; the heading wraps from +3.1 to -3.1 rad:
  // +0.0832 rad in 0.5 s.
  (void)engine.decide(frame(3, 1, 0.25, 0.0));
  FramePlan second = engine.decide(frame(0, 2, 0.5, -3.1));
  ASSERT_EQ(second.corruptions.size(), 1u);
  ASSERT_TRUE(second.corruptions[0].yaw_rate_rad_s.has_value());
  const double want = (2 * kPi - 6.2) / 0.5;
  EXPECT_NEAR(*second.corruptions[0].yaw_rate_rad_s, want, 1e-12);
  EXPECT_NEAR(second.faults[0].params.at("yaw_rate_deg_s"), want * 180 / kPi, 1e-9);
  EXPECT_EQ(second.faults[0].params.at("readout_ms"), 33.0);
  cv::Mat skewed = image.clone();
  ASSERT_TRUE(engine.render(second, skewed).is_ok());
  EXPECT_EQ(cv::norm(skewed, corruption::rolling_shutter(image, 4, want, 100), cv::NORM_INF), 0.0);
  // A frame without a pose: no rate, and the next frame with a pose measures from the last pose it
  // had.
  FramePlan blind = engine.decide(frame(0, 3, 0.75, std::nullopt));
  EXPECT_TRUE(blind.corruptions.empty());
  EXPECT_EQ(blind.faults[0].params.at("no_yaw_rate"), 1.0);
  FramePlan third = engine.decide(frame(0, 4, 1.0, -3.0));
  EXPECT_NEAR(*third.corruptions[0].yaw_rate_rad_s, 0.1 / 0.5, 1e-12);
  EXPECT_FALSE(engine.stateful(third)) << "the rate is fixed in decide(): render needs no lane";
}

TEST(RollingShutterEngineTest, CoherentIsRefused) {
  EXPECT_THROW(parse_faults(YAML::Load("[{type: rolling_shutter, coherent: true}]"), "test"),
               ConfigError);
}

}  // namespace
}  // namespace faultline::policy
