#include "runtime/frame_policy.hpp"

namespace faultline::runtime {

PlannedFrame PassThroughPolicy::plan(const transport::CameraFrameView& /*frame*/) { return {}; }

FaultDecision PassThroughPolicy::render(PlannedFrame& /*planned*/, const transport::CameraFrameView& /*frame*/,
                                        cv::Mat* /*image*/) {
  return {};
}

}  // namespace faultline::runtime
