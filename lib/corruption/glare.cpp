// Sun glare: the light layer is computed on a 1/4-resolution grid (everything in it is smooth or a
// few pixels wide at full size), upsampled, and screen-blended; it is recomputed only when the
// source moves.
#include "corruption/glare.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "rng/fast_rng.hpp"

namespace faultline::corruption {
namespace {

constexpr int kGridDivisor = 4;
constexpr double kSunTint[3] = {0.85, 0.95, 1.0};  // B, G, R: warm white
constexpr double kGhostTints[3][3] = {
    {0.55, 1.0, 0.45}, {1.0, 0.45, 0.9}, {0.35, 0.75, 1.0}};  // green, magenta, amber
constexpr double kDefaultHfovDeg =
    70.0;                               // without intrinsics: about nuScenes' camera field of view
constexpr double kSkipExponent = 12.0;  // exp(-12) < 1e-5: below one level

double smoothstep(double lo, double hi, double v) {
  const double t = std::clamp((v - lo) / (hi - lo), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

cv::Matx33d intrinsics_of(const std::optional<CameraGeometry>& g, cv::Size size) {
  if (g && g->intrinsics) return *g->intrinsics;
  const double f = size.width / (2.0 * std::tan(kDefaultHfovDeg * M_PI / 360.0));
  return {f, 0, size.width / 2.0, 0, f, size.height / 2.0, 0, 0, 1};
}

}  // namespace

GlareParams glare_params(int severity) {
  static const GlareParams kTable[] = {{0.06, 0.015, 0.0, 0.0, 0, 0.0},
                                       {0.12, 0.025, 0.35, 0.12, 0, 0.0},
                                       {0.20, 0.035, 0.55, 0.20, 2, 0.15},
                                       {0.30, 0.05, 0.75, 0.30, 3, 0.22},
                                       {0.45, 0.07, 1.0, 0.45, 4, 0.30}};
  return kTable[std::clamp(severity, 1, 5) - 1];
}

namespace {
cv::Size grid_of(cv::Size size) {
  return {std::max(1, (size.width + kGridDivisor - 1) / kGridDivisor),
          std::max(1, (size.height + kGridDivisor - 1) / kGridDivisor)};
}
}  // namespace

GlareModel::GlareModel(int severity, std::uint64_t seed, cv::Size size)
    : params_(glare_params(severity)), size_(size), up_(grid_of(size), size) {
  rng::FastRng rng(seed);
  drawn_ = {rng.uniform(0.1, 0.9) * size.width, rng.uniform(0.05, 0.45) * size.height};
  streak_angle_ = rng.uniform(0, M_PI / 3);
  for (int k = 0; k < 4; ++k) {
    ghost_pos_[k] = rng.uniform(0.3, 1.3);
    ghost_radius_[k] = rng.uniform(0.015, 0.05);
    ghost_gain_[k] = rng.uniform(0.4, 1.0);
    ghost_tint_[k] = static_cast<int>(rng.bounded(3));
  }
  source_ = drawn_;
}

void GlareModel::render_layer() {
  const cv::Size g = grid_of(size_);
  const double sx = static_cast<double>(size_.width) / g.width,
               sy = static_cast<double>(size_.height) / g.height;
  const double diag = std::hypot(size_.width, size_.height);
  const double rv2 = std::pow(0.35 * diag, 2), rb = std::max(0.5, params_.bloom * diag);
  const double width = std::max(1.0, 0.004 * diag),
               length = std::max(1e-6, params_.streak_length * diag);
  const cv::Point2d c(size_.width / 2.0, size_.height / 2.0);
  double ux[3], uy[3];
  for (int k = 0; k < 3; ++k)
    ux[k] = std::cos(streak_angle_ + k * M_PI / 3), uy[k] = std::sin(streak_angle_ + k * M_PI / 3);
  cv::Point2d gp[4];
  double gr[4];
  for (int k = 0; k < params_.ghosts; ++k)
    gp[k] = c + ghost_pos_[k] * (c - source_), gr[k] = ghost_radius_[k] * diag;
  layer_.create(g, CV_8UC3);
  cv::Mat& small = layer_;
  for (int y = 0; y < g.height; ++y) {
    cv::Vec3b* row = small.ptr<cv::Vec3b>(y);
    const double py = (y + 0.5) * sy;
    for (int x = 0; x < g.width; ++x) {
      const double px = (x + 0.5) * sx, dx = px - source_.x, dy = py - source_.y,
                   r2 = dx * dx + dy * dy;
      double light = params_.veil / (1.0 + r2 / rv2);
      const double bloom_arg = r2 / (2 * rb * rb);
      if (bloom_arg < kSkipExponent) light += std::exp(-bloom_arg);
      for (int k = 0; k < 3 && params_.streak > 0; ++k) {
        const double along = std::abs(dx * ux[k] + dy * uy[k]), perp = dx * uy[k] - dy * ux[k];
        const double arg = along / length + perp * perp / (2 * width * width);
        if (arg < kSkipExponent) light += params_.streak * std::exp(-arg);
      }
      double add[3];
      for (int ch = 0; ch < 3; ++ch) add[ch] = light * kSunTint[ch];
      for (int k = 0; k < params_.ghosts; ++k) {
        // Outside its radius a ghost adds nothing (the smoothstep is 1): skip the distance there.
        const double gx = px - gp[k].x, gy = py - gp[k].y;
        if (gx * gx + gy * gy >= gr[k] * gr[k] * (1 + 1e-9)) continue;
        const double d = std::hypot(gx, gy);
        const double disc =
            params_.ghost_strength * ghost_gain_[k] * (1.0 - smoothstep(0.7 * gr[k], gr[k], d));
        for (int ch = 0; ch < 3 && disc > 0; ++ch)
          add[ch] += disc * kGhostTints[ghost_tint_[k]][ch];
      }
      for (int ch = 0; ch < 3; ++ch) {
        row[x][ch] = static_cast<uchar>(std::lround(255.0 * std::min(1.0, visibility_ * add[ch])));
      }
    }
  }
  layer_at_ = cv::Vec3d(source_.x, source_.y, visibility_);
}

cv::Mat GlareModel::apply(const cv::Mat& bgr, const std::optional<CameraGeometry>& geometry) {
  // A geometry whose numbers are not finite (a singular K, a broken rotation) is ignored: the
  // source stays put.
  const auto finite = [](const cv::Vec3d& v) {
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
  };
  if (geometry) {
    const cv::Matx33d k = intrinsics_of(geometry, size_);
    if (!world_dir_) {
      const cv::Vec3d ray = k.inv() * cv::Vec3d(drawn_.x, drawn_.y, 1.0);
      const cv::Vec3d dir = geometry->camera_to_world * (ray / cv::norm(ray));
      if (finite(dir)) world_dir_ = dir;
    }
  }
  if (geometry && world_dir_ && finite(geometry->camera_to_world.t() * *world_dir_)) {
    const cv::Matx33d k = intrinsics_of(geometry, size_);
    const cv::Vec3d d = geometry->camera_to_world.t() * *world_dir_;
    visibility_ = smoothstep(0.0, 0.15, d[2]);
    if (d[2] > 1e-6 && finite(k * (d / d[2]))) {
      const cv::Vec3d p = k * (d / d[2]);
      // Far outside the frame only the veil reaches in; clamp so the geometry stays finite.
      const double lim = 10.0 * std::max(size_.width, size_.height);
      source_ = {std::clamp(p[0], -lim, lim), std::clamp(p[1], -lim, lim)};
    }
  }
  if (!layer_at_ || (*layer_at_)[0] != source_.x || (*layer_at_)[1] != source_.y ||
      (*layer_at_)[2] != visibility_) {
    render_layer();
  }
  cv::Mat out(bgr.size(), bgr.type());
  const int n = bgr.cols * 3;
  std::vector<uchar> light(static_cast<std::size_t>(n));
  up_.set_grid(layer_);
  for (int y = 0; y < bgr.rows; ++y) {
    up_.row(y, 0, bgr.cols, light.data());
    const uchar* s = bgr.ptr<uchar>(y);
    const uchar* l = light.data();
    uchar* o = out.ptr<uchar>(y);
    // Screen blend: 255 - (255 - I)(255 - L) / 255.
    for (int i = 0; i < n; ++i)
      o[i] = static_cast<uchar>(s[i] + ((255u - s[i]) * l[i] + 127u) / 255u);
  }
  return out;
}

}  // namespace faultline::corruption
