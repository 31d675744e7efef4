// The plug-in point of the corruption engine: per frame, a FramePolicy decides what the injector
// does (pass, corrupt, drop, black, freeze, delay). Only the pass-through policy lives here.
// Two stages, so that the injector can spread pixel work over threads and stay exact: plan() makes
// every stateful draw (schedule, RNG seeds, frame_lost) in arrival order on one thread; render()
// does the pixel work.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "common/clock.hpp"
#include "fault.pb.h"
#include "policy/fault_engine.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {

struct FaultDecision {
  msgs::FaultAction action = msgs::FAULT_ACTION_PASS;
  std::vector<msgs::ActiveFault> faults;  // what was applied (name, severity, seed, params)
  DurationNs delay_ns = 0;                // FAULT_ACTION_DELAY: forward this much later
  // JPEG passthrough only: replacement encoded bytes (e.g. a black or frozen JPEG); null =
  // original.
  std::shared_ptr<const std::vector<std::uint8_t>> replacement_jpeg;
  // Message faults (calibration_drift, timestamp_skew): applied to the output header with
  // apply_message_edit.
  policy::MessageEdit edit;
};

// Applies a decision's message faults to an output frame: capture_stamp_ns += the offset; the
// calibration drift to the intrinsics (when the frame carries all 9) and to sensor_to_ego (when
// present). What the frame does not carry stays absent. The FaultEvent keeps the true stamp.
void apply_message_edit(const policy::MessageEdit& edit, msgs::CameraFrame& frame);

// One frame's decision from plan(), handed to render().
struct PlannedFrame {
  policy::FramePlan plan;  // the engine's plan (default: pass)
  bool drop = false;       // the frame is dropped: render() only describes it, no pixels needed
  // >= 0: render() reads or writes state of this lane (a camera's coherent fault or freeze
  // history), so frames of one lane must render one at a time in plan() order. -1: render() only
  // reads configuration.
  int lane = -1;
};

class FramePolicy {
 public:
  virtual ~FramePolicy() = default;
  // Stage 1: called once per received camera frame, in arrival order, from one thread. Must not
  // throw.
  virtual PlannedFrame plan(const transport::CameraFrameView& frame) = 0;
  // Stage 2: the pixel work. `image` is the decoded bgr8 frame when the injector decodes (modified
  // in place for CORRUPT/BLACK/FREEZE), nullptr in JPEG passthrough mode. Thread-safe across lanes
  // (see PlannedFrame::lane); the frame's payload must stay valid during the call. Must not throw.
  virtual FaultDecision render(PlannedFrame& planned, const transport::CameraFrameView& frame,
                               cv::Mat* image) = 0;
  // Both stages at once, for single-threaded callers (bag convert).
  FaultDecision apply(const transport::CameraFrameView& frame, cv::Mat* image) {
    PlannedFrame p = plan(frame);
    return render(p, frame, image);
  }
};

class PassThroughPolicy final : public FramePolicy {
 public:
  PlannedFrame plan(const transport::CameraFrameView& frame) override;
  FaultDecision render(PlannedFrame& planned, const transport::CameraFrameView& frame,
                       cv::Mat* image) override;
};

}  // namespace faultline::runtime
