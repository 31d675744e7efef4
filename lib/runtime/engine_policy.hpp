// The fault engine of lib/policy as the injector's FramePolicy (kept here, beside FramePolicy, so
// that policy knows nothing of transport, codec or messages). With a decoded image (decode: true)
// the engine renders into it and the loop republishes bgr8; in JPEG passthrough it decodes only
// frames whose pixels change, corrupts and re-encodes them as JPEG q95 (the quality nuScenes-C
// used), serves black frames from a per-size cache and frozen frames from the camera's last good
// JPEG. plan() runs the engine's decide(); render() its render(), with the lane of a stateful plan
// set to the camera (coherent faults, freeze history); the black-frame cache is shared behind a
// mutex.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "policy/fault_engine.hpp"
#include "runtime/frame_policy.hpp"

namespace faultline::runtime {

class EnginePolicy final : public FramePolicy {
 public:
  explicit EnginePolicy(policy::EngineConfig config, int jpeg_quality = 95);
  PlannedFrame plan(const transport::CameraFrameView& frame) override;
  FaultDecision render(PlannedFrame& planned, const transport::CameraFrameView& frame,
                       cv::Mat* image) override;
  const policy::FaultEngine& engine() const { return engine_; }

 private:
  using Bytes = std::shared_ptr<const std::vector<std::uint8_t>>;
  FaultDecision finish(policy::FramePlan& plan, const Status& rendered);
  FaultDecision render_jpeg(policy::FramePlan& plan, const transport::CameraFrameView& frame);
  Bytes black_jpeg(const transport::CameraFrameView& frame);

  policy::FaultEngine engine_;
  int jpeg_quality_;
  std::mutex black_mutex_;                            // guards black_cache_ (any lane may fill it)
  std::map<std::pair<int, int>, Bytes> black_cache_;  // (width, height) -> encoded black frame
  std::array<Bytes, policy::kNumCameras>
      last_good_jpeg_;                       // per camera: touched only by that camera's lane
  std::atomic<bool> warned_no_pose_{false};  // rolling_shutter without ego poses: logged once
};

// The injector's policy from its parameters: the `faults` list plus the `corruption: fog/mid`
// shorthand (appended as one more fault on all cameras), the run seed, and the JPEG quality of
// re-encoded faulted frames. No faults at all gives the pass-through policy. Throws ConfigError
// naming the key and value.
std::unique_ptr<FramePolicy> make_frame_policy(const YAML::Node& faults,
                                               const std::string& corruption, std::uint64_t seed,
                                               const std::string& origin, int jpeg_quality = 95);

}  // namespace faultline::runtime
