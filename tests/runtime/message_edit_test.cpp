// apply_message_edit: a decision's message faults on an output CameraFrame, exactly; absent
// calibration stays absent.
#include <gtest/gtest.h>

#include <cmath>

#include "runtime/engine_policy.hpp"
#include "runtime/frame_policy.hpp"

namespace faultline::runtime {
namespace {

msgs::CameraFrame CalibratedFrame() {
  msgs::CameraFrame f;
  f.set_camera("CAM_FRONT");
  f.mutable_header()->set_capture_stamp_ns(1'000'000'000);
  for (double v : {1000.0, 0.0, 800.0, 0.0, 1000.0, 450.0, 0.0, 0.0, 1.0}) f.add_intrinsics(v);
  f.mutable_sensor_to_ego()->mutable_rotation()->set_w(1.0);
  f.mutable_sensor_to_ego()->mutable_translation()->set_x(1.5);
  return f;
}

TEST(MessageEditTest, AppliesStampOffsetAndDriftExactly) {
  msgs::CameraFrame f = CalibratedFrame();
  policy::MessageEdit e;
  e.stamp_offset_ns = -33'000'000;
  policy::CalibrationDrift d;
  d.pitch_rad = 0.02;
  d.dy_m = 0.1;
  d.focal_scale = 0.98;
  e.calibration = d;
  apply_message_edit(e, f);
  EXPECT_EQ(f.header().capture_stamp_ns(), 967'000'000);
  EXPECT_DOUBLE_EQ(f.intrinsics(0), 980.0);
  EXPECT_DOUBLE_EQ(f.intrinsics(4), 980.0);
  EXPECT_EQ(f.intrinsics(2), 800.0);
  EXPECT_NEAR(f.sensor_to_ego().rotation().w(), std::cos(0.01), 1e-15);
  EXPECT_NEAR(f.sensor_to_ego().rotation().y(), std::sin(0.01), 1e-15);
  EXPECT_EQ(f.sensor_to_ego().translation().x(), 1.5);
  EXPECT_DOUBLE_EQ(f.sensor_to_ego().translation().y(), 0.1);
}

TEST(MessageEditTest, EmptyEditAndMissingCalibrationChangeNothing) {
  const msgs::CameraFrame clean = CalibratedFrame();
  msgs::CameraFrame f = clean;
  apply_message_edit(policy::MessageEdit{}, f);
  EXPECT_EQ(f.SerializeAsString(), clean.SerializeAsString());
  msgs::CameraFrame bare;
  bare.mutable_header()->set_capture_stamp_ns(5);
  policy::MessageEdit e;
  e.calibration = policy::calibration_drift(5, 1);
  apply_message_edit(e, bare);
  EXPECT_EQ(bare.intrinsics_size(), 0);
  EXPECT_FALSE(bare.has_sensor_to_ego());
  EXPECT_EQ(bare.header().capture_stamp_ns(), 5);
}

// The injector's policy from a schedule: the decision carries the edit, the pixels pass untouched.
TEST(MessageEditTest, EnginePolicyHandsTheEditOnWithoutTouchingPixels) {
  auto policy = make_frame_policy(
      YAML::Load("[{type: timestamp_skew, severity: 5}, {type: calibration_drift}]"), "", 3,
      "test");
  transport::CameraFrameView view;
  view.header = CalibratedFrame();
  const std::vector<std::uint8_t> bytes = {0xFF, 0xD8, 0xFF, 0xD9};
  view.payload = bytes.data();
  view.payload_size = bytes.size();
  const FaultDecision d = policy->apply(view, nullptr);
  EXPECT_EQ(d.action, msgs::FAULT_ACTION_PASS);
  EXPECT_FALSE(d.replacement_jpeg);
  EXPECT_EQ(d.edit.stamp_offset_ns, 100'000'000);
  ASSERT_TRUE(d.edit.calibration.has_value());
  ASSERT_EQ(d.faults.size(), 2u);
  EXPECT_EQ(d.faults[0].name(), "timestamp_skew");
  EXPECT_EQ(d.faults[0].params().at("offset_ms"), 100.0);
  EXPECT_EQ(d.faults[1].params().at("focal_scale"), d.edit.calibration->focal_scale);
}

}  // namespace
}  // namespace faultline::runtime
