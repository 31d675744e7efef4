#include "runtime/frame_policy.hpp"

namespace faultline::runtime {

FaultDecision PassThroughPolicy::apply(const transport::CameraFrameView& /*frame*/, cv::Mat* /*image*/) {
  return {};
}

}  // namespace faultline::runtime
