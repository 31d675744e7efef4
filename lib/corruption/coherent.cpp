// Per-camera persistent fault state: drifting fog, falling snow, smoothly turning motion blur. The
// fog and snow state is made once; a frame reads it at that frame's offset (no per-frame remap,
// copy or redraw).
#include "corruption/coherent.hpp"

#include <algorithm>
#include <cmath>

#include "corruption/corrupt.hpp"
#include "corruption/fog.hpp"
#include "corruption/fog_kernels.hpp"
#include "corruption/motion_blur.hpp"
#include "corruption/snow.hpp"
#include "corruption/snow_kernels.hpp"

namespace faultline::corruption {
namespace {

// x mod n in [0, n) for any sign of x.
std::int64_t wrap(std::int64_t x, std::int64_t n) {
  const std::int64_t r = x % n;
  return r < 0 ? r + n : r;
}

}  // namespace

CoherentCorruptor::CoherentCorruptor(const CoherentConfig& config)
    : config_(config), rng_(config.seed) {}

void CoherentCorruptor::reset_state(cv::Size size) {
  size_ = size;
  switch (config_.type) {
    case Corruption::Fog: {
      const int n = fog_map_size(size.height, size.width);
      fog_factor_ = n >= 64 ? 4 : 1;  // fog_upsample4_row's factor, or none for tiny frames
      plasma_fractal(n / fog_factor_, fog_params(config_.severity).decay, rng_)
          .convertTo(fog_torus_, CV_32F);
      const double dir = rng_.uniform(0.0, 2.0 * M_PI);
      fog_dir_y_ = std::sin(dir);
      fog_dir_x_ = std::cos(dir);
      const auto cols = static_cast<std::size_t>(size.width);
      fog_gather_.assign(cols + 8, 0.0f);
      fog_horiz_.assign(cols + 8, 0.0f);
      fog_fixed_.create(2, 3 * size.width, CV_16U);
      break;
    }
    case Corruption::Snow: {
      // One fast-mode snow draw on a black frame gives the layer; its streak angle is the fall
      // direction.
      const SnowParams p = snow_params(config_.severity);
      const int cr = std::max(1, static_cast<int>(std::ceil(size.height / p.zoom)));
      const int cc = std::max(1, static_cast<int>(std::ceil(size.width / p.zoom)));
      cv::Mat field(cr, cc, CV_32F);
      for (int y = 0; y < cr; ++y) {
        for (int x = 0; x < cc; ++x)
          field.at<float>(y, x) = static_cast<float>(rng_.normal(p.loc, p.scale));
      }
      angle_deg_ = rng_.uniform(-135.0, -45.0);
      snow_layer_ = snow_layer_fast(field, size.height, size.width, config_.severity, angle_deg_);
      cv::flip(snow_layer_, snow_rot_, -1);  // both copies fall the same way
      break;
    }
    case Corruption::MotionBlur:
      angle_deg_ = rng_.uniform(-45.0, 45.0);
      break;
    default:
      break;
  }
}

// Fixed-point field row j of the window (torus row base_row + j, wrapping), starting at upsampled
// column c0: the torus row gathered from column c0 / factor on (wrapping), upsampled from phase c0
// % factor, then tripled into 16-bit terms. Two slots by the parity of j; the blend asks for rows j
// and j + 1 with j never decreasing.
const std::uint16_t* CoherentCorruptor::fog_fixed_row(int j, int base_row, int c0,
                                                      float add_scale) {
  auto* g = fog_fixed_.ptr<std::uint16_t>(j & 1);
  if (fog_fixed_tag_[j & 1] == j) return g;
  const int nl = fog_torus_.cols, f = fog_factor_, cols = size_.width;
  const float* row = fog_torus_.ptr<float>((base_row + j) % fog_torus_.rows);
  const int phase = c0 % f;
  const int need = (phase + cols - 1) / f + 2;  // the torus values the upsampling reads
  for (int i = 0, c = (c0 / f) % nl; i < need; ++i, c = c + 1 == nl ? 0 : c + 1)
    fog_gather_[i] = row[c];
  const float* field = fog_gather_.data();
  if (f == 4) {
    fog_upsample4_row(fog_gather_.data(), fog_horiz_.data(), phase + cols);
    field = fog_horiz_.data() + phase;
  }
  fog_fixed_field_row(field, g, cols, add_scale);
  fog_fixed_tag_[j & 1] = j;
  return g;
}

cv::Mat CoherentCorruptor::apply_fog(const cv::Mat& bgr, double t) {
  const int f = fog_factor_, rows = bgr.rows, cols = bgr.cols;
  const std::int64_t side = static_cast<std::int64_t>(fog_torus_.rows) * f;
  // Whole-pixel offsets, so rows lerp at the fixed-point blend's quarter steps; rounding moves a
  // field this smooth (quarter resolution) by at most half of one pixel's drift.
  const auto r0 = static_cast<int>(wrap(std::llround(t * config_.fog_drift_px * fog_dir_y_), side));
  const auto c0 = static_cast<int>(wrap(std::llround(t * config_.fog_drift_px * fog_dir_x_), side));
  fog_offset_ = {c0, r0};
  // The blend constants as fog_fast computes them: out = src * m / (m + a) + 255 * a * m / (m + a)
  // * field.
  std::uint8_t mx = 0;
  for (int y = 0; y < rows && mx < 255; ++y) {
    mx = fog_max_u8(bgr.ptr<std::uint8_t>(y), static_cast<std::size_t>(cols) * 3, mx);
  }
  const auto m = static_cast<float>(mx / 255.0);
  const auto strength = static_cast<float>(fog_params(config_.severity).strength);
  const float scale = m / (m + strength);
  const float add_scale = strength * 255.0f * scale;
  const auto scale16 = static_cast<std::uint16_t>(std::min(std::lround(scale * 65536.0f), 65535L));
  fog_fixed_tag_[0] = fog_fixed_tag_[1] = -1;  // the rows depend on this frame's offset and maximum
  const int base_row = r0 / f;
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < rows; ++y) {
    const int p = r0 + y;
    const int j = p / f - base_row, k = p % f;
    const std::uint16_t* a = fog_fixed_row(j, base_row, c0, add_scale);
    const std::uint16_t* b = k ? fog_fixed_row(j + 1, base_row, c0, add_scale) : a;
    fog_blend_fixed_row(bgr.ptr<std::uint8_t>(y), a, b, k, out.ptr<std::uint8_t>(y), cols, scale16);
  }
  return out;
}

cv::Mat CoherentCorruptor::apply_snow(const cv::Mat& bgr, double t) const {
  // Snow falls along its streak: the streak offsets point along (sin, cos) of the angle. Output
  // pixel (y, x) reads both copies at ((y - dy) mod rows, (x - dx) mod cols): each row is two runs
  // of the stored layers, no copy.
  const double rad = angle_deg_ * M_PI / 180.0;
  const int rows = bgr.rows, cols = bgr.cols;
  const std::int64_t dy = std::llround(-t * config_.snow_fall_px * std::sin(rad));
  const std::int64_t dx = std::llround(-t * config_.snow_fall_px * std::cos(rad));
  const auto sx = static_cast<int>(wrap(-dx, cols));  // layer column of output column 0
  const int split = cols - sx;  // output columns [0, split) read layer columns [sx, cols)
  const SnowParams p = snow_params(config_.severity);
  const auto b = static_cast<float>(p.blend);
  const auto one_minus_b =
      static_cast<float>(1.0 - p.blend);  // formed in double first, as snow_blend_fast does
  cv::Mat out(bgr.size(), bgr.type());
  for (int y = 0; y < rows; ++y) {
    const auto ly = static_cast<int>(wrap(y - dy, rows));
    const std::uint8_t* layer = snow_layer_.ptr<std::uint8_t>(ly);
    const std::uint8_t* rot = snow_rot_.ptr<std::uint8_t>(ly);
    const std::uint8_t* src = bgr.ptr<std::uint8_t>(y);
    std::uint8_t* dst = out.ptr<std::uint8_t>(y);
    snow_kernels::blend_fast_row(src, layer + sx, rot + sx, false, dst, split, b, one_minus_b);
    if (sx > 0)
      snow_kernels::blend_fast_row(src + 3 * split, layer, rot, false, dst + 3 * split, sx, b,
                                   one_minus_b);
  }
  return out;
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
    case Corruption::Fog:
      return apply_fog(bgr, t);
    case Corruption::Snow:
      return apply_snow(bgr, t);
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
    default:
      return corrupt(bgr, config_.type, config_.severity, rng_);
  }
}

Result<cv::Mat> CoherentCorruptor::apply(const cv::Mat& bgr, const FrameContext& ctx) {
  if (!is_sensor_fault(config_.type)) return apply(bgr);
  if (Status s = validate_input(bgr, config_.severity); !s) return s;
  const std::int64_t index = frames_++;
  if (config_.severity == 0) return bgr.clone();
  if (!sensor_)
    sensor_ = std::make_unique<SensorFaultState>(config_.type, config_.severity, config_.seed);
  return sensor_->apply(bgr, index, ctx);
}

}  // namespace faultline::corruption
