// Sun glare and lens flare (Faultline's own): a bright light source near or in the field of view.
// Its light scattered in the lens adds a veiling glare that falls off away from the source, a
// saturated bloom around it, diffraction streaks from a six-blade aperture (three lines through the
// source), and at higher severities ghost discs (internal reflections) along the line from the
// source through the image centre. The light is added with a screen blend, so nothing darkens and
// white stays white. The source is drawn once from the seed at a position in the image (the sun low
// above the horizon). When frames carry the camera's pose, the source is a fixed direction in the
// world from the first posed frame on, so its image position follows the ego heading (and pitch,
// roll); once it is behind the camera the glare fades out.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>

#include "corruption/grid_upsample.hpp"
#include "corruption/sensor_fault.hpp"

namespace faultline::corruption {

struct GlareParams {
  double
      veil;  // veiling glare at the source, share of full scale; half of it at 0.35 image diagonals
  double bloom;           // bloom radius (sd), share of the image diagonal
  double streak;          // streak strength at the source (0 = none)
  double streak_length;   // streak decay length, share of the image diagonal
  int ghosts;             // ghost discs
  double ghost_strength;  // their peak strength
};
// Severity 1..5: a faint veil (0.06, no streaks) up to the sun in the frame (veil 0.45, bloom 7 %
// of the diagonal, full streaks, four ghosts); docs/faults.md lists the table.
GlareParams glare_params(int severity);

class GlareModel {
 public:
  GlareModel(int severity, std::uint64_t seed, cv::Size size);

  // The glared frame; `geometry` (when given) moves the source as described above. CV_8UC3 of the
  // model's size.
  cv::Mat apply(const cv::Mat& bgr, const std::optional<CameraGeometry>& geometry);

  cv::Size size() const { return size_; }
  cv::Point2d source_px() const {
    return source_;
  }  // where the last frame had the source (may be off-image)
  double visibility() const {
    return visibility_;
  }  // 1 in front of the camera, fading to 0 behind it

 private:
  void render_layer();

  GlareParams params_;
  cv::Size size_;
  cv::Point2d drawn_;    // the seeded position
  double streak_angle_;  // of the first streak line (rad)
  double ghost_pos_[4], ghost_radius_[4], ghost_gain_[4];
  int ghost_tint_[4];
  std::optional<cv::Vec3d>
      world_dir_;  // the source's direction in the world, from the first posed frame
  cv::Point2d source_;
  double visibility_ = 1;
  cv::Mat layer_;  // CV_8UC3 light added (0..255) on the 1/4 grid; rendered for layer_at_
  GridUpsampler up_;
  std::optional<cv::Vec3d> layer_at_;  // (x, y, visibility) the layer was rendered for
};

}  // namespace faultline::corruption
