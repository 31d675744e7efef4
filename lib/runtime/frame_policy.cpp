#include "runtime/frame_policy.hpp"

namespace faultline::runtime {

void apply_message_edit(const policy::MessageEdit& edit, msgs::CameraFrame& frame) {
  if (edit.stamp_offset_ns != 0) {
    frame.mutable_header()->set_capture_stamp_ns(frame.header().capture_stamp_ns() +
                                                 edit.stamp_offset_ns);
  }
  if (!edit.calibration) return;
  policy::Calibration c;
  const bool has_k = frame.intrinsics_size() == 9;
  if (has_k) {
    for (int i = 0; i < 9; ++i) c.intrinsics[static_cast<std::size_t>(i)] = frame.intrinsics(i);
  }
  const bool has_extrinsics = frame.has_sensor_to_ego();
  if (has_extrinsics) {
    const auto& q = frame.sensor_to_ego().rotation();
    const auto& t = frame.sensor_to_ego().translation();
    c.rotation_wxyz = {q.w(), q.x(), q.y(), q.z()};
    c.translation_m = {t.x(), t.y(), t.z()};
  }
  policy::apply_drift(*edit.calibration, c);
  if (has_k) {
    for (int i = 0; i < 9; ++i) frame.set_intrinsics(i, c.intrinsics[static_cast<std::size_t>(i)]);
  }
  if (has_extrinsics) {
    auto* q = frame.mutable_sensor_to_ego()->mutable_rotation();
    auto* t = frame.mutable_sensor_to_ego()->mutable_translation();
    q->set_w(c.rotation_wxyz[0]);
    q->set_x(c.rotation_wxyz[1]);
    q->set_y(c.rotation_wxyz[2]);
    q->set_z(c.rotation_wxyz[3]);
    t->set_x(c.translation_m[0]);
    t->set_y(c.translation_m[1]);
    t->set_z(c.translation_m[2]);
  }
}

PlannedFrame PassThroughPolicy::plan(const transport::CameraFrameView& /*frame*/) { return {}; }

FaultDecision PassThroughPolicy::render(PlannedFrame& /*planned*/,
                                        const transport::CameraFrameView& /*frame*/,
                                        cv::Mat* /*image*/) {
  return {};
}

}  // namespace faultline::runtime
