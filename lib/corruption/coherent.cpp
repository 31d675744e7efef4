// Per-camera persistent fault state: drifting fog, falling snow, smoothly turning motion blur.
#include "corruption/coherent.hpp"

#include <algorithm>
#include <cmath>

#include "corruption/corrupt.hpp"
#include "corruption/fog.hpp"
#include "corruption/motion_blur.hpp"
#include "corruption/snow.hpp"

namespace faultline::corruption {
namespace {

// Cyclic shift (np.roll) of a single-channel image by whole pixels.
cv::Mat roll(const cv::Mat& m, int dy, int dx) {
  const int rows = m.rows, cols = m.cols;
  dy = ((dy % rows) + rows) % rows;
  dx = ((dx % cols) + cols) % cols;
  cv::Mat out(m.size(), m.type());
  for (int y = 0; y < rows; ++y) {
    const uchar* src = m.ptr<uchar>(y);
    uchar* dst = out.ptr<uchar>((y + dy) % rows);
    std::copy(src, src + (cols - dx), dst + dx);
    std::copy(src + (cols - dx), src + cols, dst);
  }
  return out;
}

}  // namespace

CoherentCorruptor::CoherentCorruptor(const CoherentConfig& config) : config_(config), rng_(config.seed) {}

void CoherentCorruptor::reset_state(cv::Size size) {
  size_ = size;
  switch (config_.type) {
    case Corruption::Fog: {
      const int n = fog_map_size(size.height, size.width);
      fog_factor_ = n >= 64 ? 4 : 1;
      fog_low_ = plasma_fractal(n / fog_factor_, fog_params(config_.severity).decay, rng_);
      const double dir = rng_.uniform(0.0, 2.0 * M_PI);
      fog_dir_y_ = std::sin(dir);
      fog_dir_x_ = std::cos(dir);
      break;
    }
    case Corruption::Snow: {
      // One fast-mode snow draw on a black frame gives the layer; its streak angle is the fall direction.
      const SnowParams p = snow_params(config_.severity);
      const int cr = std::max(1, static_cast<int>(std::ceil(size.height / p.zoom)));
      const int cc = std::max(1, static_cast<int>(std::ceil(size.width / p.zoom)));
      cv::Mat field(cr, cc, CV_32F);
      for (int y = 0; y < cr; ++y) {
        for (int x = 0; x < cc; ++x) field.at<float>(y, x) = static_cast<float>(rng_.normal(p.loc, p.scale));
      }
      angle_deg_ = rng_.uniform(-135.0, -45.0);
      snow_layer_ = snow_layer_fast(field, size.height, size.width, config_.severity, angle_deg_);
      break;
    }
    case Corruption::MotionBlur: angle_deg_ = rng_.uniform(-45.0, 45.0); break;
    default: break;
  }
}

Result<cv::Mat> CoherentCorruptor::apply(const cv::Mat& bgr) {
  if (is_sensor_fault(config_.type)) return apply(bgr, FrameContext{});
  if (Status s = validate_input(bgr, config_.severity); !s) return s;
  if (config_.severity == 0) {
    ++frames_;
    return bgr.clone();
  }
  if (frames_ == 0 || bgr.size() != size_) reset_state(bgr.size());
  const double t = static_cast<double>(frames_);
  ++frames_;
  switch (config_.type) {
    case Corruption::Fog: {
      const cv::Mat field = upsample_torus_window(fog_low_, fog_factor_, t * config_.fog_drift_px * fog_dir_y_,
                                                  t * config_.fog_drift_px * fog_dir_x_, size_.height, size_.width);
      return fog_blend_fast(bgr, field, fog_params(config_.severity).strength);
    }
    case Corruption::Snow: {
      // Snow falls along its streak: the streak offsets point along (sin, cos) of the angle.
      const double rad = angle_deg_ * M_PI / 180.0;
      const int dy = static_cast<int>(std::lround(-t * config_.snow_fall_px * std::sin(rad)));
      const int dx = static_cast<int>(std::lround(-t * config_.snow_fall_px * std::cos(rad)));
      cv::Mat rot;
      cv::flip(snow_layer_, rot, -1);  // both copies fall the same way
      return snow_blend_fast(bgr, roll(snow_layer_, dy, dx), roll(rot, dy, dx), config_.severity);
    }
    case Corruption::MotionBlur: {
      if (frames_ > 1) {
        // Ornstein-Uhlenbeck step towards 0 with reflection at the bounds of the reference's range.
        double a = angle_deg_ - 0.02 * angle_deg_ + config_.angle_step_deg * rng_.standard_normal();
        if (a > 45.0) a = 90.0 - a;
        if (a < -45.0) a = -90.0 - a;
        angle_deg_ = std::clamp(a, -45.0, 45.0);
      }
      return motion_blur_fast(bgr, config_.severity, angle_deg_);
    }
    default: return corrupt(bgr, config_.type, config_.severity, rng_);
  }
}

Result<cv::Mat> CoherentCorruptor::apply(const cv::Mat& bgr, const FrameContext& ctx) {
  if (!is_sensor_fault(config_.type)) return apply(bgr);
  if (Status s = validate_input(bgr, config_.severity); !s) return s;
  const std::int64_t index = frames_++;
  if (config_.severity == 0) return bgr.clone();
  if (!sensor_) sensor_ = std::make_unique<SensorFaultState>(config_.type, config_.severity, config_.seed);
  return sensor_->apply(bgr, index, ctx);
}

}  // namespace faultline::corruption
