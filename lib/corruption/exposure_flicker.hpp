// Exposure flicker and auto-exposure hunting (Faultline's own): the frame's exposure error over
// time, in stops (EV).
// - Flicker: lights driven by mains or LED PWM beat against the frame rate; sampled by short
// exposures this is a
//   fast oscillation of the frame's brightness (beat 2-5.5 Hz: near frame-to-frame at 12 Hz).
// - Hunting: an auto-exposure loop that overshoots and oscillates slowly (0.3-0.8 Hz) around its
// target, in
//   episodes that swell and fade (envelope 0.03-0.08 Hz).
// - Banding (severity >= 3): a rolling shutter reads rows at different phases of the light:
// horizontal bands that
//   drift down the frame.
// Exposure acts on linear light; the frame is gamma-encoded (about 2.2), so a gain of 2^EV
// multiplies the stored values by 2^(EV / 2.2), saturating at 255. The frequencies and phases are
// drawn once from the seed and persist.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

namespace faultline::corruption {

struct ExposureFlickerParams {
  double flicker_ev;  // peak exposure error of the flicker (stops)
  double hunting_ev;  // peak exposure error of the AE hunting (stops)
  double band_depth;  // peak relative gain of the rolling-shutter bands (0 = none)
};
// Severity 1..5: (0.1, 0.1, 0), (0.2, 0.25, 0), (0.3, 0.45, 0.05), (0.45, 0.7, 0.10), (0.6, 1.0,
// 0.20).
ExposureFlickerParams exposure_flicker_params(int severity);

class ExposureFlickerModel {
 public:
  ExposureFlickerModel(int severity, std::uint64_t seed);

  // Exposure error (stops) of the whole frame at time t (s): flicker + hunting. Finite for finite
  // t.
  double exposure_ev(double time_s) const;
  // Relative gain of row y of `rows` at time t from the bands (1 without banding).
  double band_gain(int y, int rows, double time_s) const;
  // The frame exposed with that error: out = min(255, I * (2^EV * band)^(1/2.2)), rounded.
  cv::Mat apply(const cv::Mat& bgr, double time_s) const;

 private:
  ExposureFlickerParams params_;
  double flicker_hz_, flicker_phase_;
  double hunt_hz_, hunt_phase_, envelope_hz_, envelope_phase_;
  double bands_per_frame_, band_phase_;
};

}  // namespace faultline::corruption
