// The fault engine: given the schedule and a run seed, decides per camera frame which faults fire
// (decide) and applies them to the decoded pixels (render). Pure (no I/O, no clocks): time comes
// from the frames' capture stamps, relative to the first frame seen. decide() is not thread-safe:
// call it from one thread in arrival order. render() keeps its state per camera (coherent
// corruptors, the last good frame), so frames of different cameras may render concurrently; see
// render() for the order frames of one camera need.
//
// - Image corruptions: a fresh RNG per (run seed, camera, source_seq) (seeding.hpp), or one
// CoherentCorruptor per
//   camera (restarted when a ramp changes the severity).
// - camera_crash: without `cameras`, the dead set is drawn once per run like RoboBEV (numpy mode:
//   NumpyRandomState(seed), k choice draws with replacement; a ramp to severity k uses the first k
//   draws). With `cameras`, exactly those cameras crash (scripted faults).
// - frame_lost: one draw of 6 uniforms per frame instant, cameras in reference order; a camera's
// n-th eligible
//   frame uses the n-th draw, so numpy mode reproduces the reference masks for a seed and the
//   result does not depend on the interleaving of cameras. Dropped iff u < severity/6.
// - Several faults on one frame: corruptions stack in list order; the strongest temporal outcome
// wins
//   (drop > black > freeze > delay).
// - rolling_shutter: the ego yaw rate between a camera's consecutive frames with ego poses
// (decide() keeps the
//   last heading per camera); without a previous pose the frame passes unchanged (no pixel work)
//   and the fault says no_yaw_rate.
// - stale_frames: a delay of stale_frames_ns() (message_faults.hpp), stamps kept; per camera the
//   frames stay in capture order when the lag ends (keep_stale_order).
// - calibration_drift / timestamp_skew: no action of their own; they fill FramePlan::edit
// (message_faults.hpp), with
//   the drift's direction seeded per (run seed, fault, camera) so it persists across the camera's
//   frames.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/clock.hpp"
#include "common/status.hpp"
#include "corruption/coherent.hpp"
#include "policy/fault_spec.hpp"
#include "policy/message_faults.hpp"
#include "policy/temporal_draws.hpp"
#include "rng/numpy_legacy.hpp"

namespace faultline::policy {

struct FrameInfo {
  std::string camera;            // "CAM_FRONT", ...; unknown cameras get no faults
  std::uint64_t source_seq = 0;  // the source's seq of this frame (per camera)
  StampNs capture_stamp_ns = 0;
  bool is_key_frame = true;
  std::optional<double>
      ego_yaw_rad;      // ego heading at capture (from the frame's ego pose); none = no pose
  double focal_px = 0;  // horizontal focal length (K[0]); 0 = unknown
  // The camera's orientation in the world (ego pose x calibration) and intrinsics, when the frame
  // carries them: the glare source follows it.
  std::optional<corruption::CameraGeometry> geometry;
};

enum class Action { Pass, Corrupt, Drop, Black, Freeze, Delay };
const char* to_string(Action action);

struct AppliedFault {
  std::string name;
  int severity = 0;
  std::uint64_t seed = 0;
  std::string rng;                       // "numpy" or "fast"
  std::map<std::string, double> params;  // angle_deg, delay_ms, u, p, ...
};

struct FramePlan {
  Action action = Action::Pass;
  std::vector<AppliedFault> faults;
  DurationNs delay_ns = 0;
  int camera = -1;
  struct Step {  // one image corruption to apply in render()
    std::size_t fault_index = 0;
    std::size_t applied_index = 0;  // its entry in `faults`
    int severity = 0;
    std::uint64_t seed = 0;
    std::optional<double>
        yaw_rate_rad_s;  // rolling_shutter: from this and the camera's previous ego pose
    double focal_px = 0;
  };
  std::vector<Step> corruptions;
  MessageEdit edit;  // message faults: stamp offset, calibration error (no pixels)
  corruption::FrameContext
      context;  // time since the first frame and the camera geometry, for the sensor faults
  bool needs_pixels() const;  // render() has work to do
};

struct EngineConfig {
  std::vector<FaultSpec> faults;
  std::uint64_t seed = 0;  // run seed
};

class FaultEngine {
 public:
  explicit FaultEngine(EngineConfig config);
  ~FaultEngine();

  FramePlan decide(const FrameInfo& frame);

  // Applies the plan to `image` (CV_8UC3) in place: corruptions, then black or freeze. Keeps the
  // camera's last good frame (PASS/CORRUPT/DELAY output) when some fault freezes. Must see every
  // frame that is not dropped. Thread-safety: calls for different cameras may run concurrently.
  // Calls for one camera whose plans are stateful(plan) must run one at a time in decide() order;
  // other plans only read the configuration.
  Status render(FramePlan& plan, cv::Mat& image);
  // The plan's render reads or writes the camera's state (a coherent corruption, or freeze
  // history).
  bool stateful(const FramePlan& plan) const;

  bool freezes() const { return freezes_; }  // some fault may freeze: the caller keeps history
  const EngineConfig& config() const { return config_; }

 private:
  double lost_uniform(std::size_t i, const FaultSpec& spec, int camera);
  struct StaleHit {
    std::size_t applied_index = 0;  // its entry in FramePlan::faults
    int severity = 0;
  };
  void keep_stale_order(FramePlan& plan, StampNs stamp_ns, const std::optional<StaleHit>& stale);
  void add_message_fault(const FaultSpec& spec, std::size_t i, int cam, int severity,
                         MessageEdit& edit, AppliedFault& f) const;

  EngineConfig config_;
  bool freezes_ = false;
  std::optional<StampNs> first_stamp_ns_;
  std::vector<std::vector<std::vector<int>>>
      crash_sets_;  // per fault: dead set at severity k at [k]
  std::vector<std::vector<std::array<double, kNumCameras>>>
      lost_draws_;  // per fault (numpy): uniforms per instant
  std::vector<std::unique_ptr<rng::NumpyRandomState>>
      lost_streams_;  // per fault (numpy): the run's stream
  std::vector<std::array<std::uint64_t, kNumCameras>>
      lost_counters_;  // per fault: eligible frames per camera
  // Per camera, so that render() calls of different cameras touch disjoint objects.
  struct Coherent {
    std::unique_ptr<corruption::CoherentCorruptor> corruptor;
    int severity = 0;
  };
  std::array<std::map<std::size_t, Coherent>, kNumCameras>
      coherent_;  // fault index -> its corruptor
  std::array<cv::Mat, kNumCameras> last_good_;
  struct Heading {
    StampNs stamp_ns = 0;
    double yaw_rad = 0;
  };
  std::array<std::optional<Heading>, kNumCameras> last_heading_;  // decide() only
  struct StaleHeld {
    std::optional<StampNs> release_ns;  // capture stamp + lag of the camera's last held frame
    int severity = 0;                   // of its last stale_frames hit (reported on catch_up)
  };
  std::array<StaleHeld, kNumCameras> stale_held_;  // decide() only
  std::optional<double> yaw_rate(int cam, const FrameInfo& frame);
};

}  // namespace faultline::policy
