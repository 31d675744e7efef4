// Temporal coherence for streaming (none of the references has it): one small stateful object per
// camera keeps a fault consistent across that camera's frames instead of redrawing it every frame.
// The state is made once (on the first frame, and again when the frame size changes) and each frame
// only reads it at that frame's offset, so a coherent fault costs about what its non-coherent fast
// form costs, less the drawing.
// - Fog: one toroidal plasma field per camera (quarter resolution, normalised over the whole
// torus), drifting by
//   `fog_drift_px` per frame in a direction drawn once. A frame shows the field's window at the
//   drift's offset rounded to whole pixels, upsampled (corner-aligned bilinear, wrapping) and
//   blended in the fast mode's 16-bit fixed point, within 1 level of fog_blend_fast over
//   upsample_torus_window at that offset.
// - Snow: one snow layer per camera, falling along its streak direction by `snow_fall_px` per frame
// (wrapping).
// - Motion Blur: the angle follows a mean-reverting random walk (step sd `angle_step_deg`) kept in
// [-45°, 45°].
// - Dark: the tone curve is fixed by the severity; the sensor noise is redrawn each frame (it is
// temporally white).
// - Bright, Color Quant, Contrast, Saturate, Pixelate, JPEG, Gaussian blur: deterministic,
// identical every frame.
// - The pointwise noises (gaussian, shot, impulse, speckle, ISO): redrawn each frame, as sensor
// noise is white in time.
// - The sensor faults (soiling, water_drops, glare, exposure_flicker): one model per camera drawn
// from the seed
//   (sensor_fault.hpp), rendered at each frame's time and pose.
// Fast-mode generators throughout. Same config + same frames -> same outputs. Not thread-safe; one
// per camera.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "common/status.hpp"
#include "corruption/sensor_fault.hpp"
#include "corruption/types.hpp"
#include "rng/fast_rng.hpp"

namespace faultline::corruption {

struct CoherentConfig {
  Corruption type = Corruption::Fog;
  int severity = 1;             // 0 = off, 1..5
  std::uint64_t seed = 0;       // per camera: derive distinct seeds for distinct cameras
  double fog_drift_px = 1.5;    // pixels per frame the fog field moves
  double snow_fall_px = 8.0;    // pixels per frame the snow layer moves along its streak
  double angle_step_deg = 1.0;  // sd of the per-frame motion-blur angle change
};

class CoherentCorruptor {
 public:
  explicit CoherentCorruptor(const CoherentConfig& config);

  // Corrupts the next frame of this camera (CV_8UC3 BGR). A change of frame size restarts the
  // persistent state.
  Result<cv::Mat> apply(const cv::Mat& bgr);
  // The same with what the frame carries besides pixels (time, camera pose); only the sensor faults
  // read it.
  Result<cv::Mat> apply(const cv::Mat& bgr, const FrameContext& ctx);

  std::int64_t frames() const { return frames_; }
  double angle_deg() const {
    return angle_deg_;
  }  // Motion Blur's current angle (or Snow's streak angle)
  // Fog's state, for tests: the low-resolution torus (CV_32F, values in [0, 1]), its upsampling
  // factor, and the last frame's window offset (x = column, y = row) in upsampled pixels, in [0,
  // torus side * factor).
  const cv::Mat& fog_torus() const { return fog_torus_; }
  int fog_factor() const { return fog_factor_; }
  cv::Point fog_offset() const { return fog_offset_; }

 private:
  void reset_state(cv::Size size);
  cv::Mat apply_fog(const cv::Mat& bgr, double t);
  cv::Mat apply_snow(const cv::Mat& bgr, double t) const;
  const std::uint16_t* fog_fixed_row(int j, int base_row, int c0, float add_scale);

  CoherentConfig config_;
  rng::FastRng rng_;
  std::int64_t frames_ = 0;
  cv::Size size_;
  cv::Mat fog_torus_;   // CV_32F toroidal plasma map at 1 / fog_factor_ resolution
  int fog_factor_ = 1;  // upsampling factor of fog_torus_
  double fog_dir_y_ = 0, fog_dir_x_ = 0;
  cv::Point fog_offset_;
  // Per-frame scratch, kept to avoid reallocating: one torus row gathered from the window's first
  // column, its horizontal upsampling, and two fixed-point field rows (fog_fixed_field_row) tagged
  // with their window row.
  std::vector<float> fog_gather_, fog_horiz_;
  cv::Mat fog_fixed_;
  int fog_fixed_tag_[2] = {-1, -1};
  cv::Mat snow_layer_;  // CV_8U H x W
  cv::Mat snow_rot_;    // the layer rotated by 180° (the reference's second copy), made once
  double angle_deg_ = 0;
  std::unique_ptr<SensorFaultState> sensor_;  // the sensor faults' model, made on first use
};

}  // namespace faultline::corruption
