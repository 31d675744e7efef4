// The fault engine as the injector's FramePolicy. With a decoded image (decode: true) the engine renders into it
// and the loop republishes bgr8; in JPEG passthrough it decodes only frames whose pixels change, corrupts and
// re-encodes them as JPEG q95 (the quality nuScenes-C used), serves black frames from a per-size cache and
// frozen frames from the camera's last good JPEG.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "policy/fault_engine.hpp"
#include "runtime/frame_policy.hpp"

namespace faultline::policy {

class EnginePolicy final : public runtime::FramePolicy {
 public:
  explicit EnginePolicy(EngineConfig config, int jpeg_quality = 95);
  runtime::FaultDecision apply(const transport::CameraFrameView& frame, cv::Mat* image) override;
  const FaultEngine& engine() const { return engine_; }

 private:
  using Bytes = std::shared_ptr<const std::vector<std::uint8_t>>;
  runtime::FaultDecision finish(FramePlan& plan, const Status& rendered);
  Bytes black_jpeg(const transport::CameraFrameView& frame);

  FaultEngine engine_;
  int jpeg_quality_;
  std::map<std::pair<int, int>, Bytes> black_cache_;  // (width, height) -> encoded black frame
  std::array<Bytes, kNumCameras> last_good_jpeg_;
};

// The injector's policy from its parameters: the `faults` list plus the `corruption: fog/mid` shorthand (appended
// as one more fault on all cameras) and the run seed. No faults at all gives the pass-through policy.
// Throws ConfigError naming the key and value.
std::unique_ptr<runtime::FramePolicy> make_frame_policy(const YAML::Node& faults, const std::string& corruption,
                                                        std::uint64_t seed, const std::string& origin);

}  // namespace faultline::policy
