// The plug-in point of the corruption engine: per frame, a FramePolicy decides what the injector
// does (pass, corrupt, drop, black, freeze, delay). Only the pass-through policy lives here.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <vector>

#include "common/clock.hpp"
#include "fault.pb.h"
#include "transport/typed.hpp"

namespace faultline::runtime {

struct FaultDecision {
  msgs::FaultAction action = msgs::FAULT_ACTION_PASS;
  std::vector<msgs::ActiveFault> faults;  // what was applied (name, severity, seed, params)
  DurationNs delay_ns = 0;                // FAULT_ACTION_DELAY: forward this much later
  // JPEG passthrough only: replacement encoded bytes (e.g. a black or frozen JPEG); null = original.
  std::shared_ptr<const std::vector<std::uint8_t>> replacement_jpeg;
};

class FramePolicy {
 public:
  virtual ~FramePolicy() = default;
  // Called once per received camera frame, in arrival order, from the injector thread.
  // `image` is the decoded bgr8 frame when the injector decodes (modify it in place for
  // CORRUPT/BLACK/FREEZE), nullptr in JPEG passthrough mode. Must not throw.
  virtual FaultDecision apply(const transport::CameraFrameView& frame, cv::Mat* image) = 0;
};

class PassThroughPolicy final : public FramePolicy {
 public:
  FaultDecision apply(const transport::CameraFrameView& frame, cv::Mat* image) override;
};

}  // namespace faultline::runtime
